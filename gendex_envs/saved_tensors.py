"""Checks on tensors loaded from an untrusted torch archive (a stage policy's ``policy.pth``, a BC checkpoint)
with ``torch.load(weights_only=True)``: that loader runs no code, but it builds each tensor from the shape, strides
and offset the archive records beside the storage, so what it returns can be far larger than the file."""

from __future__ import annotations

from collections.abc import Iterable


def check_tensor_sizes(tensors: Iterable, path, error: type[Exception], max_bytes: int) -> None:
    """Refuse (``error`` naming ``path``) loaded tensors that do not each hold their own bytes. A 4-byte storage
    with stride 0 loads as a view of 2**40 elements, which the first computation on it (``isfinite``) would
    materialise: 4 TB from a 1.5 kB file, or 37 s and 2 GB for 2**31. ``tensors``: (name, tensor) pairs. Each must
    be contiguous and inside its storage, and all of them together at most ``max_bytes`` (tensors may share one
    storage)."""
    total = 0
    for name, v in tensors:
        n = v.numel() * v.element_size()
        if not v.is_contiguous() or v.storage_offset() * v.element_size() + n > v.untyped_storage().nbytes():
            raise error(f"{path}: tensor {str(name)[:100]!r} of shape {tuple(v.shape)[:8]} is a strided view, not "
                        "values of its own; a saved weight is contiguous and holds its bytes")
        total += n
        if total > max_bytes:
            raise error(f"{path}: its tensors hold more than {max_bytes} bytes; at most {max_bytes} are allowed")
