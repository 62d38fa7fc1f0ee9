"""The runtime guard around reward code: restricted builtins for every reward module, and a PEP 578 audit hook that
refuses process, network, file, ctypes and introspection events while untrusted code is running.

Two fences, in addition to the static check (:mod:`gendex_envs.code_check`) and the read-only view
(:mod:`gendex_envs.reward_view`):

1. **Restricted builtins and module copies** (untrusted modules). :func:`restricted_builtins` is the
   ``__builtins__`` such a module executes with: only :data:`SAFE_BUILTINS` (no ``open``, ``exec``, ``eval``,
   ``compile``, ``vars``, ``globals``, no ``__build_class__``; ``getattr``/``hasattr`` refuse ``_`` names and names
   outside the allow-list) and an ``__import__`` that admits only :data:`ALLOWED_IMPORTS` and hands out read-only
   copies of them holding exactly the allow-listed names (:func:`_proxy`,
   :data:`~gendex_envs.code_check.rules.MODULE_MEMBERS`; any other name raises :class:`UntrustedCodeError` naming
   the module and the attribute). Python looks ``__import__`` up in
   the running frame's builtins, so an ``import os`` inside a reward function fails even when ``os`` is already
   loaded, which no audit hook sees; C code that imports on the module's behalf is refused the same way.

2. **An audit hook** (:func:`untrust`), installed the first time a task folder that is not trusted is loaded and
   kept for the rest of the process (audit hooks cannot be removed). It judges each sensitive event by the Python
   stack: when a frame of an untrusted folder's code is on it, process spawning (``subprocess``, ``os.system``,
   ``os.exec*``, ``os.fork``, ``pty``), network (``socket``, ``urllib``, ``http.client``...), ``ctypes``, file
   writes and deletions, reading files outside the Python installation, directory listings, ``exec``/``compile``
   of code that is not a library module, adding audit hooks, tracing and frame introspection are refused with
   :class:`UntrustedCodeError`. Deferred misbehaviour does not escape it: the test is *whose code is running*, not
   how long the task has run, so step 10 000 is judged as step 1. The same process keeps full rights for the
   user's own code (writing a dataset after ``gym.make`` of a downloaded task works), which a process-wide ban
   could not offer.

C extensions that write files themselves (``numpy``'s ``tofile``, torch's serialization and archive classes) raise
no audit event: the module copies do not offer them and the static check refuses those names. Tensor methods cannot
be withheld in-process, so :data:`~gendex_envs.code_check.rules.TENSOR_METHODS` is enforced by the static check,
with the confined worker process as the wall behind it. Python has no in-process isolation, so
these fences hold together, not one by one; a process boundary (the probe's child) is the stronger one.

Trust: the package's preview module and the reward modules of the repository's task folder (``generated_tasks/``)
whose bytes the trust record lists (:mod:`gendex_envs.trust_record`, ``generated_tasks/TRUSTED.sha256``: what people
reviewed and recorded with ``gendex trust``) are trusted. Anything else (a file there that is new or changed, such as
``gendex generate``'s output, ``GENDEX_TASKS_PATH``, a downloaded task) is untrusted unless the user says so:
``gym.make(id, trust_remote_code=True)``, ``TaskEnv(..., trust_remote_code=True)``, or
``GENDEX_TRUST_REMOTE_CODE=1`` in the environment (as ``transformers`` names it).
"""

from __future__ import annotations

import builtins
import difflib
import logging
import os
import sys
import threading
import types
from pathlib import Path
from types import FrameType

from gendex_envs.code_check.rules import (
    ALLOWED_ATTRIBUTE_NAMES,
    ALLOWED_BUILTINS,
    ALLOWED_MODULES,
    ALLOWED_PACKAGES,
    ALTERNATIVES,
    MODULE_MEMBERS,
)
from gendex_envs.errors import GenDexError

log = logging.getLogger(__name__)

TRUST_ENV = "GENDEX_TRUST_REMOTE_CODE"
"""Set to 1 to trust every task folder (as ``trust_remote_code=True`` on every env)."""

SAFE_BUILTINS = ALLOWED_BUILTINS | {"True", "False", "None", "NotImplemented", "Ellipsis"}
"""The builtins a reward module runs with (the static check's allow-list plus the constants)."""

ALLOWED_IMPORTS: dict[str, frozenset[str] | None] = {
    "__future__": None, **dict.fromkeys(ALLOWED_MODULES),
    **{package: frozenset(m[len(package) + 1:] for m in ALLOWED_MODULES if m.startswith(package + "."))
       for package in ALLOWED_PACKAGES},
}
"""Module -> the names ``from MODULE import ...`` may take (None: any); the static check's modules and packages."""

_PROCESS = ("subprocess.", "os.system", "os.exec", "os.spawn", "os.fork", "os.forkpty", "os.posix_spawn", "os.kill",
            "os.killpg", "os.wait", "pty.", "os.startfile", "signal.")
_NETWORK = ("socket.", "urllib.", "http.client.", "ftplib.", "smtplib.", "poplib.", "imaplib.", "nntplib.",
            "telnetlib.", "webbrowser.", "ssl.")
_FILES = ("os.remove", "os.unlink", "os.rename", "os.replace", "os.rmdir", "os.mkdir", "os.makedirs", "os.chmod",
          "os.chown", "os.chdir", "os.link", "os.symlink", "os.truncate", "os.utime", "os.listdir", "os.scandir",
          "os.putenv", "os.unsetenv", "os.chflags", "os.lchmod", "os.lchown", "os.setxattr", "os.removexattr",
          "shutil.", "glob.", "tempfile.", "fcntl.", "mmap.", "sqlite3.", "shelve.", "dbm.")
_CODE = ("ctypes.", "cffi.", "sys.addaudithook", "sys.settrace", "sys.setprofile", "sys._getframe",
         "sys._current_frames", "sys.set_asyncgen_hooks", "sys.setrecursionlimit", "builtins.input",
         "builtins.breakpoint", "code.__new__", "function.__new__", "marshal.", "pickle.find_class",
         "object.__setattr__", "object.__delattr__", "object.__getattr__", "gc.", "cpython.", "_thread.",
         "threading.", "resource.", "os.setuid", "os.setgid", "os.setsid", "os.nice", "faulthandler.")
_DENIED = _PROCESS + _NETWORK + _FILES + _CODE
_CALLER_JUDGED = ("sys._getframe", "object.__getattr__", "object.__setattr__", "object.__delattr__", "marshal.",
                  "os.listdir", "os.scandir")
_JUDGED = _DENIED + ("open", "exec", "compile", "import")
_JUDGED_EXACT = frozenset(e for e in _JUDGED if "." not in e or e.startswith(("sys.", "builtins.")))
_JUDGED_HEADS = frozenset(e.split(".")[0] for e in _JUDGED if "." in e and not e.startswith(("sys.", "builtins.")))
"""The hook's fast path: most audit events (``builtins.id`` fires ~50 times per env step) are dismissed by one set
lookup of their name or of the module part of it; ``sys.*`` and ``builtins.*`` events are matched exactly."""
_IMPORT_MACHINERY = ("<frozen importlib", "<frozen zipimport")


class UntrustedCodeError(GenDexError, PermissionError):
    """Untrusted reward code tried something the runtime guard refuses (a process, the network, a file...)."""


# ---------------------------------------------------------------------------------------------- restricted builtins
class ModuleView(types.ModuleType):
    """A reward-code copy of a module: its allow-listed names only. A name it lacks is refused with
    :class:`UntrustedCodeError` naming the module and the attribute and listing what is allowed, not a bare
    ``AttributeError`` (dunder probes by Python's own machinery still get ``AttributeError``)."""

    def __getattr__(self, name: str):
        if name.startswith("__"):
            raise AttributeError(name)
        module = self.__name__
        allowed = MODULE_MEMBERS.get(module, frozenset())
        close = [n for n in ALTERNATIVES.get(name, ()) if n in allowed]
        close += [n for n in difflib.get_close_matches(str(name), sorted(allowed), n=5, cutoff=0.6) if n not in close]
        raise UntrustedCodeError(
            f"reward code may not use {module}.{str(name)[:80]}: only the allow-listed pure functions of {module} "
            f"are available to it ({len(allowed)} names, gendex_envs.code_check.rules.MODULE_MEMBERS)"
            + (f"; nearest allowed: {', '.join(close)}" if close else ""))

    def __setattr__(self, name: str, value) -> None:
        raise UntrustedCodeError(f"reward code may not change the module {self.__name__} (setting {name!s:.80})")

    def __delattr__(self, name: str) -> None:
        raise UntrustedCodeError(f"reward code may not change the module {self.__name__} (deleting {name!s:.80})")


_proxies: dict[str, ModuleView] = {}


class _TensorTypeMeta(type):
    def __instancecheck__(cls, obj) -> bool:
        import torch

        return isinstance(obj, torch.Tensor)

    def __subclasscheck__(cls, sub) -> bool:
        import torch

        return issubclass(sub, torch.Tensor)

    def __call__(cls, *args, **kwargs):
        raise UntrustedCodeError("reward code may not call torch.Tensor(...): with sizes it hands out uninitialised "
                                 "memory (torch.empty); build tensors with torch.zeros, torch.full or torch.tensor")


class TensorType(metaclass=_TensorTypeMeta):
    """What ``torch.Tensor`` is in reward code's copy of torch: ``isinstance(x, torch.Tensor)`` and annotations
    work; calling it raises :class:`UntrustedCodeError` (the legacy constructor ``torch.Tensor(n)`` is
    ``torch.empty(n)``: uninitialised memory, which could carry state from one call to the next)."""


def _proxy(name: str) -> ModuleView:
    """The copy of module ``name`` reward code gets: exactly the names
    :data:`~gendex_envs.code_check.rules.MODULE_MEMBERS` allows for it (an allow-list: torch's functions that
    compute on tensors, ``math``'s pure functions, ``reward_terms``), allowed submodules as copies themselves.
    ``torch.frombuffer``, ``torch.empty``, ``torch.as_strided``, ``torch.get_file_path``, ``torch.save`` or
    ``torch.os`` do not exist for it, even if the static check were bypassed. Tensor *methods* cannot be withheld
    in-process (every tensor carries them), so :data:`~gendex_envs.code_check.rules.TENSOR_METHODS` is enforced by
    the static check, and the confined worker process is the wall behind it. (A dunder could still reach the real
    module: Python has no in-process isolation, which is why the static check refuses every dunder and the audit
    hook watches.)"""
    if name not in _proxies:
        import importlib

        real = importlib.import_module(name)
        copy = ModuleView(name, f"reward-code view of {name}")
        public = {}
        for member in MODULE_MEMBERS[name]:
            value = getattr(real, member)
            public[member] = _proxy(value.__name__) if isinstance(value, types.ModuleType) else value
        if name == "torch" and "Tensor" in public:
            public["Tensor"] = TensorType  # a type to name, not to call: Tensor(n) is torch.empty(n)
        copy.__dict__.update(public)
        _proxies[name] = copy
    return _proxies[name]


def _guarded_import(name: str, globals=None, locals=None, fromlist=(), level: int = 0):
    if level != 0:
        raise UntrustedCodeError(f"reward code may not use relative imports (from {'.' * level}{name} import ...)")
    allowed = ALLOWED_IMPORTS.get(name, ())
    if allowed == ():
        raise UntrustedCodeError(f"reward code may not import {name!r}; allowed: {sorted(ALLOWED_IMPORTS)}")
    extra = sorted(set(fromlist or ()) - allowed) if allowed is not None else []
    if extra:
        raise UntrustedCodeError(f"reward code may not import {extra} from {name!r}; allowed: {sorted(allowed)}")
    if name == "__future__":
        return builtins.__import__(name, globals, locals, fromlist, level)
    # `import a.b.c` binds the top package; `from a.b import c` gets a.b itself
    return _proxy(name if fromlist else name.split(".")[0])


def _public(name) -> str:
    if not isinstance(name, str) or name.startswith("_"):
        raise UntrustedCodeError(f"reward code may read public attributes only, not {str(name)[:80]!r}")
    if name not in ALLOWED_ATTRIBUTE_NAMES:
        raise UntrustedCodeError(f"reward code may not read the attribute {name[:80]!r}: only the allow-listed tensor "
                                 "methods, env view members and module functions (gendex_envs.code_check.rules)")
    return name


def _getattr(obj, name, *default):
    return getattr(obj, _public(name), *default)


def _hasattr(obj, name) -> bool:
    return hasattr(obj, _public(name))


def restricted_builtins() -> dict:
    """A fresh ``__builtins__`` mapping for one reward module (see the module doc): ``getattr``/``hasattr`` refuse
    private and dunder names."""
    _warm_torch()
    table = {name: getattr(builtins, name) for name in SAFE_BUILTINS}
    table.update(__import__=_guarded_import, getattr=_getattr, hasattr=_hasattr)
    return table


_warmed = False


def _warm_torch() -> None:
    """Let torch's C++ side make, from trusted code, the one import it makes lazily: the first tensor built from
    Python data with a ``device`` imports ``torch.storage`` through the *calling frame's* ``__import__``, which in
    reward code is :func:`_guarded_import`; refused there, torch fails with an INTERNAL ASSERT instead of building
    ``torch.tensor([...], device=env.device)`` (PickUpBottle's reward does that)."""
    global _warmed
    if not _warmed:
        import torch

        torch.tensor([0.0], device="cpu")
        _warmed = True


# ---------------------------------------------------------------------------------------------- trust
_untrusted: tuple[str, ...] = ()
_trusted_extra: set[str] = set()
_lock = threading.Lock()
_busy = threading.local()
_installed = False


def _folder(path: str | Path) -> str:
    return str(Path(path).resolve()) + os.sep


def trust(folder: str | Path) -> None:
    """Mark ``folder``'s code as trusted for this process (``trust_remote_code=True``)."""
    global _untrusted
    f = _folder(folder)
    with _lock:
        _trusted_extra.add(f)
        _untrusted = tuple(u for u in _untrusted if not u.startswith(f))


def trusts_everything() -> bool:
    """``GENDEX_TRUST_REMOTE_CODE=1``: the user trusts every task folder."""
    return os.environ.get(TRUST_ENV, "").strip().lower() in ("1", "true", "yes")


def is_trusted(path: str | Path, data: bytes | None = None) -> bool:
    """Whether code at ``path`` runs without the guard: everything when ``GENDEX_TRUST_REMOTE_CODE=1``, the package
    itself, folders passed to :func:`trust`, and, in the repository's task folder (``generated_tasks/``), only the
    files whose bytes match the trust record (:mod:`gendex_envs.trust_record`: a new or changed file there is
    untrusted, wherever it came from; a folder there is trusted when every ``.py`` file in it is). ``data``: the
    bytes about to run, judged instead of the file's. ``path`` is judged where it lies: its folder resolved, its own
    name not followed (a link in a download to a file under ``generated_tasks/`` is not trusted code)."""
    if trusts_everything():
        return True
    from gendex_envs.registry import REPO_TASKS_DIR

    named = Path(path).absolute()
    p = _folder(named.parent) + named.name + os.sep  # a link is judged where it lies, not by where it points
    package = _folder(Path(__file__).parent)
    if p.startswith((package, *_trusted_extra)):
        return True
    tasks = _folder(REPO_TASKS_DIR)
    if not p.startswith(tasks):
        return False
    from gendex_envs import trust_record

    return trust_record.is_recorded(tasks, p[len(tasks):-1], data)


def untrust(folder: str | Path) -> None:
    """Run every later event raised while code under ``folder`` is on the stack through the guard (installs the
    audit hook on first use; it stays for the rest of the process)."""
    global _untrusted, _installed
    f = _folder(folder)
    with _lock:
        if f not in _untrusted:
            _untrusted = (*_untrusted, f)
            log.info("runtime guard: code under %s is untrusted", f)
        if not _installed:
            sys.addaudithook(_hook)
            _installed = True


def untrusted_folders() -> tuple[str, ...]:
    return _untrusted


# ---------------------------------------------------------------------------------------------- the hook
def _library_prefixes() -> tuple[str, ...]:
    roots = {sys.prefix, sys.base_prefix, sys.exec_prefix, str(Path(__file__).resolve().parent)}
    return tuple(str(Path(r).resolve()) + os.sep for r in roots)


_LIBRARY = _library_prefixes()


def _culprit(frame: FrameType | None) -> str | None:
    """The first untrusted file on the stack from ``frame`` outwards, or None."""
    while frame is not None:
        name = frame.f_code.co_filename
        if name.startswith(_untrusted):
            return name
        frame = frame.f_back
    return None


def _caller(frame: FrameType | None) -> FrameType | None:
    """The nearest frame that is not the import machinery (who asked for an import)."""
    while frame is not None and frame.f_code.co_filename.startswith(_IMPORT_MACHINERY):
        frame = frame.f_back
    return frame


def _writes(mode, flags) -> bool:
    if isinstance(mode, str) and any(c in mode for c in "wax+"):
        return True
    return isinstance(flags, int) and bool(flags & (os.O_WRONLY | os.O_RDWR | os.O_CREAT | os.O_TRUNC | os.O_APPEND))


def _refusal(event: str, args: tuple, frame: FrameType) -> str | None:
    """Why ``event`` is refused with untrusted code on the stack, or None when it is allowed."""
    if event.startswith(_DENIED):
        if event.startswith(_CALLER_JUDGED):
            # introspection by a library the reward code called (logging, warnings) and unmarshalling by the
            # import machinery loading a library module are theirs: judged by who called, not who is on the stack
            asker = _caller(frame)
            if asker is None or not asker.f_code.co_filename.startswith(_untrusted):
                return None
            return "listing folders" if event.startswith(("os.listdir", "os.scandir")) else "introspection"
        for group, why in ((_PROCESS, "starting processes"), (_NETWORK, "network access"), (_FILES, "touching files")):
            if event.startswith(group):
                return why
        return "ctypes, tracing or introspection"
    if event == "open":
        path, mode, flags = (tuple(args) + (None, None, None))[:3]
        if _writes(mode, flags):
            return "writing files"
        if isinstance(path, int):
            return None  # an fd already open: the opener was judged
        text = os.fsdecode(path) if isinstance(path, str | bytes | os.PathLike) else str(path)
        return None if str(Path(text).resolve()).startswith(_LIBRARY) else "reading files"
    if event in ("exec", "compile"):
        # libraries build code (dataclasses, namedtuple, torch's serialization): judged by who asked
        asker = _caller(frame)
        if asker is not None and asker.f_code.co_filename.startswith(_untrusted):
            return "running code it built itself"
        return None
    if event == "import":
        asker = _caller(frame)
        if asker is not None and asker.f_code.co_filename.startswith(_untrusted):
            name = args[0] if args else ""
            return None if name in ALLOWED_IMPORTS else f"importing {name!r}"
    return None


def _hook(event: str, args: tuple) -> None:
    if event not in _JUDGED_EXACT and event.partition(".")[0] not in _JUDGED_HEADS:
        return
    if not event.startswith(_JUDGED) or getattr(_busy, "on", False):
        return
    _busy.on = True
    try:
        frame = sys._getframe(1)  # noqa: SLF001 - the stack is what the hook judges
        culprit = _culprit(frame)
        if culprit is None:
            return
        why = _refusal(event, args, frame)
    finally:
        _busy.on = False
    if why is not None:
        detail = ", ".join(repr(a)[:80] for a in tuple(args)[:2])
        raise UntrustedCodeError(f"runtime guard: untrusted code in {culprit} may not do {event}({detail}) "
                                 f"({why}); reward code reads the env view and returns tensors, nothing else. Trust "
                                 f"the folder with trust_remote_code=True or {TRUST_ENV}=1 if you wrote it")
