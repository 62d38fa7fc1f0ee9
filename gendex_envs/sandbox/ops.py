"""The operations a compiled reward call may replay in the parent: name <-> torch function, one table for both sides.

A reward function traced in the confined worker (:mod:`gendex_envs.sandbox.trace`) becomes a straight-line graph
of torch calls; the parent replays it (:mod:`gendex_envs.sandbox.replay`) only through this table. It is built from
the allow-list reward code is held to (:mod:`gendex_envs.code_check.rules`: torch functions, tensor methods and
attributes) plus the operators Python reaches through tensor dunders and the in-place arithmetic that augmented
assignment (``x += y``) becomes, minus the operations a replay must not run (:data:`NOT_REPLAYED`). Both sides build
it the same way, so a name means the same function in the worker and in the parent; the parent never resolves a
name outside it.
"""

from __future__ import annotations

import inspect

import torch

from gendex_envs.code_check.rules import TENSOR_METHODS, TORCH_FUNCTIONS

NOT_REPLAYED = frozenset({
    # output size set by tensor values, not shapes: a replay would allocate what the data says
    "torch.nonzero", "torch.argwhere", "torch.masked_select", "torch.unique", "torch.unique_consecutive",
    "torch.bincount", "torch.repeat_interleave", "torch.nn.functional.one_hot", "Tensor.nonzero",
    "Tensor.argwhere", "Tensor.masked_select", "Tensor.unique", "Tensor.repeat_interleave",
    # contraction cost not bounded by the sizes of inputs and outputs
    "torch.einsum", "torch.tensordot", "torch.chain_matmul", "torch.linalg.multi_dot",
    # leaves the tensor world or the device
    "Tensor.cpu", "Tensor.tolist",
    # iterative linear algebra: work far beyond the size of what goes in and out (a matrix power, a decomposition)
    "torch.det", "torch.logdet", "torch.slogdet", "torch.inverse", "torch.pinverse", "torch.matrix_power",
    "torch.matrix_exp", "torch.cholesky", "torch.qr", "torch.svd", "Tensor.det", "Tensor.inverse",
    "torch.linalg.det", "torch.linalg.slogdet", "torch.linalg.inv", "torch.linalg.pinv", "torch.linalg.solve",
    "torch.linalg.solve_triangular", "torch.linalg.lstsq", "torch.linalg.cholesky", "torch.linalg.qr",
    "torch.linalg.svd", "torch.linalg.svdvals", "torch.linalg.eig", "torch.linalg.eigvals", "torch.linalg.eigh",
    "torch.linalg.eigvalsh", "torch.linalg.matrix_rank", "torch.linalg.matrix_power", "torch.linalg.matrix_exp",
    "torch.linalg.matrix_norm", "torch.linalg.cond", "torch.linalg.tensorinv", "torch.linalg.tensorsolve",
    "torch.linalg.lu", "torch.linalg.lu_factor", "torch.linalg.lu_solve",
    # special functions whose work comes from an argument's value (series summed until they converge, a range as
    # long as an argument): zeta loops about -q times for a negative q, mvlgamma builds arange(p)
    "torch.special.zeta", "torch.polygamma", "torch.special.polygamma", "torch.mvlgamma",
    "torch.special.multigammaln", "torch.special.gammainc", "torch.special.gammaincc",
})
"""Allow-listed names a compiled call does not replay: a graph holding one is not compiled (the worker keeps
serving that function)."""

IN_PLACE = (
    "add_", "sub_", "mul_", "div_", "true_divide_", "floor_divide_", "remainder_", "fmod_", "pow_", "clamp_",
    "clamp_min_", "clamp_max_", "bitwise_and_", "bitwise_or_", "bitwise_xor_", "logical_and_", "logical_or_",
    "logical_xor_", "__iand__", "__ior__", "__ixor__", "__ilshift__", "__irshift__", "masked_fill_", "fill_",
    "zero_", "copy_", "__setitem__",
)
"""In-place methods augmented assignment and subscript assignment become (the static check allows them only on
tensors the function created; a replay runs them only on its own copies)."""

OPERATORS = (
    "__add__", "__radd__", "__sub__", "__rsub__", "__mul__", "__rmul__", "__truediv__", "__rtruediv__", "__div__",
    "__rdiv__", "__floordiv__", "__rfloordiv__", "__mod__", "__rmod__", "__pow__", "__rpow__", "__matmul__",
    "__rmatmul__", "__neg__", "__pos__", "__abs__", "__invert__", "__and__", "__rand__", "__or__", "__ror__",
    "__xor__", "__rxor__", "__lshift__", "__rlshift__", "__rshift__", "__rrshift__", "__eq__", "__ne__", "__lt__",
    "__le__", "__gt__", "__ge__", "__getitem__", "__len__", "__bool__", "__float__", "__int__", "__index__",
    "__iadd__", "__isub__", "__imul__", "__itruediv__", "__ifloordiv__", "__imod__", "__ipow__",
)
"""Tensor dunders: Python's operators on tensors."""

SHAPE_ARGUMENTS = frozenset({
    "torch.zeros", "torch.ones", "torch.full", "torch.arange", "torch.linspace", "torch.logspace", "torch.eye",
    "torch.tensor", "torch.as_tensor", "torch.scalar_tensor", "torch.tril_indices", "torch.triu_indices",
    "torch.vander", "torch.linalg.vander", "torch.fft.fftfreq", "torch.fft.rfftfreq",
    "Tensor.new_tensor", "Tensor.new_zeros", "Tensor.new_ones", "Tensor.new_full", "Tensor.expand", "Tensor.view",
    "Tensor.reshape", "Tensor.repeat", "Tensor.tile", "Tensor.broadcast_to", "Tensor.unflatten", "Tensor.narrow",
    "Tensor.unfold", "torch.reshape", "torch.tile", "torch.broadcast_to", "torch.unflatten", "torch.narrow",
    "torch.nn.functional.pad", "torch.diag_embed", "torch.diagflat", "torch.combinations", "torch.topk",
    "Tensor.topk", "torch.kthvalue", "Tensor.kthvalue", "torch.histc",
})
"""Operations whose output size or work comes from their arguments beyond the first tensor (sizes, counts, steps):
in a replay those arguments must be constants of the graph, never tensors, so that the work is what the graph
states (:mod:`gendex_envs.sandbox.replay` checks it before anything runs)."""


def _build() -> tuple[dict[str, object], dict[object, str]]:
    by_name: dict[str, object] = {}
    for module_name, names in sorted(TORCH_FUNCTIONS.items()):
        module = torch
        for part in module_name.split(".")[1:]:
            module = getattr(module, part)
        for name in sorted(names):
            obj = getattr(module, name, None)
            if obj is None or isinstance(obj, type) or not callable(obj):
                continue  # dtypes, constants and types: values in a graph, not operations
            by_name[f"{module_name}.{name}"] = obj
    for name in sorted(TENSOR_METHODS) + list(IN_PLACE) + list(OPERATORS):
        static = inspect.getattr_static(torch.Tensor, name, None)
        if static is None:
            continue
        if hasattr(static, "__get__") and not callable(static):  # an attribute: the mode sees its getter
            by_name[f"Tensor.{name}"] = static.__get__
        else:
            by_name[f"Tensor.{name}"] = getattr(torch.Tensor, name)
    refused = [by_name[k] for k in NOT_REPLAYED if k in by_name]  # by function: an alias is refused as well
    by_name = {k: v for k, v in by_name.items() if not any(v == r for r in refused)}
    by_function: dict[object, str] = {}
    for name, fn in by_name.items():
        try:
            by_function.setdefault(fn, name)
        except TypeError:  # an unhashable callable cannot be looked up by the tracer
            continue
    return by_name, by_function


OPS, NAMES = _build()
"""``OPS``: name -> the function a replay calls; ``NAMES``: function (as the tracer sees it) -> its first name."""
SHAPE_FUNCTIONS = tuple(OPS[n] for n in sorted(SHAPE_ARGUMENTS) if n in OPS)
"""The functions of :data:`SHAPE_ARGUMENTS` (compared by function, so an alias of one is held the same way)."""


GUARDS = frozenset({
    "Tensor.__bool__", "Tensor.__float__", "Tensor.__int__", "Tensor.__index__", "Tensor.__len__", "Tensor.item",
    "Tensor.size", "Tensor.dim", "Tensor.numel", "Tensor.nelement", "Tensor.shape", "Tensor.dtype", "Tensor.device",
    "Tensor.ndim", "Tensor.is_cuda", "Tensor.is_floating_point", "Tensor.is_complex", "Tensor.equal",
    "Tensor.allclose", "Tensor.type", "torch.equal", "torch.allclose", "torch.is_nonzero", "torch.is_tensor",
    "torch.is_floating_point", "torch.is_complex", "torch.numel", "torch.result_type", "torch.can_cast",
    "torch.promote_types", "torch.broadcast_shapes",
})
"""Operations whose result is a Python value (a guard of the recording); every other operation's result is a
tensor or a sequence of tensors, whatever a graph states."""
GUARD_FUNCTIONS = tuple(OPS[n] for n in sorted(GUARDS) if n in OPS)


def is_guard(name: str) -> bool:
    fn = OPS[name]
    return any(fn == f for f in GUARD_FUNCTIONS)


def takes_shape_arguments(name: str) -> bool:
    fn = OPS[name]
    return any(fn == f for f in SHAPE_FUNCTIONS)
