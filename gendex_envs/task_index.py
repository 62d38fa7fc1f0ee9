"""The registration index of a task root: what registering a version needs, without parsing its spec.

Registering a version needs its id (the folder names) and its time limit (``max_episode_steps``, which Gymnasium's
spec carries). Parsing a spec costs about 7.5 ms (YAML and validation), so a library of 2 000 versions would take
15 s to import; ``<root>/index.json`` holds, per version folder, the SHA-256 of its spec file and the time limit
read from it. Registration reads each spec's bytes (about 40 µs a version), and uses the indexed time limit only
where the digest matches; a version the index does not know, or whose spec changed since, is parsed as before, and
a stale index is reported with the command that renews it (``gendex store index ROOT``); publishing a version
into a root that has an index records it there (:func:`add_to_index`). The spec itself is parsed and
validated when an env is made. A test holds the committed library's index equal to a fresh build.

The index of a folder on ``$GENDEX_TASKS_PATH`` is untrusted data like the rest of that folder: it is read with a
size bound, every field is checked (types, ranges, folder names), and an index that does not pass is ignored (every
spec of that root is parsed) with a warning naming the problem.
"""

from __future__ import annotations

import hashlib
import json
import logging
from dataclasses import dataclass
from pathlib import Path

from gendex_envs.errors import TaskSpecError

log = logging.getLogger(__name__)

INDEX_NAME = "index.json"
"""File name of a task root's index (beside the ``<Name>/`` folders)."""
FORMAT = 1
MAX_INDEX_BYTES = 64 << 20
"""Largest index read (about 150 bytes a version: room for 400 000 versions)."""
_HEX = frozenset("0123456789abcdef")


@dataclass(frozen=True)
class IndexEntry:
    """What registration needs of one version folder (``<Name>/v<N>`` relative to the root)."""

    spec_sha256: str
    max_episode_steps: int


def spec_digest(spec_file: Path) -> str:
    """SHA-256 of a spec file's bytes."""
    return hashlib.sha256(spec_file.read_bytes()).hexdigest()


def index_path(root: str | Path) -> Path:
    return Path(root) / INDEX_NAME


def build_index(root: str | Path) -> dict[str, IndexEntry]:
    """The index of every version under ``root``, each spec parsed (:class:`TaskSpecError` names a spec that does
    not load: an index never records a version that registration would refuse)."""
    from gendex_envs.task_version import versions_in

    out = {}
    for version in versions_in(root):
        spec = version.load_spec_unchecked()
        out[f"{version.name}/v{version.version}"] = IndexEntry(spec_digest(version.files.spec), spec.max_episode_steps)
    return out


def index_json(entries: dict[str, IndexEntry]) -> dict:
    return {"format": FORMAT, "generated_by": "gendex index",
            "versions": {k: {"spec_sha256": e.spec_sha256, "max_episode_steps": e.max_episode_steps}
                         for k, e in sorted(entries.items())}}


def write_index(root: str | Path) -> Path:
    """Build and write ``<root>/index.json`` (atomically); returns its path."""
    from gendex_envs.atomic_io import write_text

    entries = build_index(root)
    path = write_text(index_path(root), json.dumps(index_json(entries), indent=1, sort_keys=True) + "\n")
    log.info("indexed %d versions in %s", len(entries), path)
    return path


def add_to_index(version) -> bool:
    """Record a just-published ``version`` in its root's index, when the root has a valid one (True); a root
    without an index keeps none. Two runs publishing at once may drop each other's entry: registration then parses
    that spec and says the index is stale, nothing worse."""
    from gendex_envs.atomic_io import write_text

    root = version.tasks_root
    entries = load_index(root)
    if entries is None:
        return False
    try:
        spec = version.load_spec_unchecked()
    except TaskSpecError as exc:  # registration will refuse it with this reason; the index never records it
        log.warning("not indexing %s: %s", version.env_id, exc)
        return False
    entries[f"{version.name}/v{version.version}"] = IndexEntry(spec_digest(version.files.spec), spec.max_episode_steps)
    write_text(index_path(root), json.dumps(index_json(entries), indent=1, sort_keys=True) + "\n")
    return True


class TaskIndexError(TaskSpecError):
    """An index file that cannot be used (registration then parses every spec of its root)."""


def _entry(key: object, value: object, max_steps: int) -> IndexEntry:
    from gendex_envs.spec import TASK_NAME_RE
    from gendex_envs.task_version import VERSION_DIR

    if not isinstance(key, str) or key.count("/") != 1:
        raise TaskIndexError(f"version key {str(key)[:80]!r} is not '<Name>/v<N>'")
    name, version = key.split("/")
    if not TASK_NAME_RE.fullmatch(name) or not VERSION_DIR.fullmatch(version):
        raise TaskIndexError(f"version key {key[:80]!r} is not '<Name>/v<N>' (CamelCase ASCII name, v and digits)")
    if not isinstance(value, dict) or set(value) != {"spec_sha256", "max_episode_steps"}:
        raise TaskIndexError(f"{key}: an entry holds exactly spec_sha256 and max_episode_steps")
    digest, steps = value["spec_sha256"], value["max_episode_steps"]
    if not isinstance(digest, str) or len(digest) != 64 or not set(digest) <= _HEX:
        raise TaskIndexError(f"{key}: spec_sha256 is not 64 lower-case hex digits")
    if type(steps) is not int or not 1 <= steps <= max_steps:
        raise TaskIndexError(f"{key}: max_episode_steps {steps!r} is not an integer in [1, {max_steps}]")
    return IndexEntry(digest, steps)


def load_index(root: str | Path) -> dict[str, IndexEntry] | None:
    """The index of ``root`` (None when there is none); an index that is not valid is reported and ignored."""
    from gendex_envs.spec import MAX_STEPS

    path = index_path(root)
    try:
        if not path.is_file() or path.is_symlink():
            return None
        if path.stat().st_size > MAX_INDEX_BYTES:
            raise TaskIndexError(f"{path.stat().st_size} bytes, more than MAX_INDEX_BYTES = {MAX_INDEX_BYTES}")
        data = json.loads(path.read_bytes())
        if not isinstance(data, dict) or data.get("format") != FORMAT or not isinstance(data.get("versions"), dict):
            raise TaskIndexError(f"not a format-{FORMAT} index (an object with 'format': {FORMAT} and 'versions')")
        return {k: _entry(k, v, MAX_STEPS) for k, v in data["versions"].items()}
    except (OSError, ValueError, RecursionError) as exc:
        log.warning("ignoring %s (%s); every spec in %s is parsed instead: run `gendex store index %s` to renew it",
                    path, exc, root, root)
        return None


def stale_entries(root: str | Path) -> dict[str, str]:
    """How ``root``'s index differs from its folders: ``<Name>/v<N>`` -> what is wrong (empty when it matches)."""
    have = load_index(root)
    if have is None:
        return {"*": f"no valid {INDEX_NAME}"}
    want = build_index(root)
    out = {k: "not indexed" for k in want.keys() - have.keys()}
    out.update({k: "indexed but no such version" for k in have.keys() - want.keys()})
    out.update({k: f"indexed {have[k]}, folder has {want[k]}" for k in want.keys() & have.keys()
                if have[k] != want[k]})
    return out
