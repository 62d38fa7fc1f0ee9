"""OS confinement of the reward worker (:mod:`gendex_envs.sandbox.worker`): rlimits, no new privileges, no
capabilities, Landlock (files, TCP, signals) and a seccomp filter (processes, sockets, tracing, the kernel's
admin interfaces).

The worker calls :func:`confine` once, after importing torch and before it receives any untrusted source; every
step is irreversible for the process. Stdlib only (plus ``pyseccomp``, a ctypes binding of the system's
libseccomp, which resolves syscall names and the architecture check): the worker imports this file without the
``gendex_envs`` package.

Landlock goes through the three syscalls with ``ctypes`` here rather than the ``landlock`` package: its only
release is an alpha (1.0.0.dev5) that knows no network rules (ABI 4) nor scopes (ABI 6) and decides failure by a
stale ``errno`` instead of the return value. The layer is small and each of its rules is tested by a payload
(``tests/security/test_sandbox.py``).
"""

from __future__ import annotations

import ctypes
import errno
import os
import resource
import signal
import sys

# ---------------------------------------------------------------------------------------------- limits
MEMORY_LIMIT_BYTES = 4 << 30
"""RLIMIT_AS of the worker: torch's CPU build maps about 1.2 GiB of address space idle; reward code needs a few MB."""
CPU_LIMIT_S = 24 * 3600
"""RLIMIT_CPU of the worker (its whole life): a backstop; each call is bounded by the parent's wall-clock limit."""
OPEN_FILES_LIMIT = 32
"""RLIMIT_NOFILE: the worker holds its two pipes and what torch opened before confinement."""

# ---------------------------------------------------------------------------------------------- prctl
PR_SET_PDEATHSIG = 1
PR_SET_DUMPABLE = 4
PR_SET_NO_NEW_PRIVS = 38
_libc = ctypes.CDLL(None, use_errno=True)
_libc.syscall.restype = ctypes.c_long


class ConfinementError(RuntimeError):
    """A wall could not be raised (the kernel lacks it, or a call failed); the worker must not run code."""


def _check(result: int, what: str) -> int:
    if result < 0:
        err = ctypes.get_errno()
        raise ConfinementError(f"{what} failed: {os.strerror(err)} (errno {err})")
    return result


def die_with_parent(parent_pid: int) -> None:
    """SIGKILL when the parent dies; exits now if it already has."""
    _check(_libc.prctl(PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0), "prctl(PR_SET_PDEATHSIG)")
    if os.getppid() != parent_pid:
        os._exit(70)


# ---------------------------------------------------------------------------------------------- Landlock
_SYS_CREATE_RULESET, _SYS_ADD_RULE, _SYS_RESTRICT_SELF = 444, 445, 446  # the same number on every architecture
_RULE_PATH_BENEATH = 1
FS_EXECUTE, FS_WRITE_FILE, FS_READ_FILE, FS_READ_DIR = 1 << 0, 1 << 1, 1 << 2, 1 << 3
_FS_ABI = {1: (1 << 13) - 1, 2: (1 << 14) - 1, 3: (1 << 15) - 1, 5: (1 << 16) - 1}
NET_BIND_TCP, NET_CONNECT_TCP = 1 << 0, 1 << 1
SCOPE_ABSTRACT_UNIX_SOCKET, SCOPE_SIGNAL = 1 << 0, 1 << 1


class _RulesetAttr(ctypes.Structure):
    _fields_ = [("handled_access_fs", ctypes.c_uint64), ("handled_access_net", ctypes.c_uint64),
                ("scoped", ctypes.c_uint64)]


class _PathBeneath(ctypes.Structure):
    _pack_ = 1
    _fields_ = [("allowed_access", ctypes.c_uint64), ("parent_fd", ctypes.c_int32)]


def landlock_abi() -> int:
    """The kernel's Landlock ABI version, 0 when it has none (not Linux, not built in, disabled at boot)."""
    if not sys.platform.startswith("linux"):
        return 0
    ctypes.set_errno(0)
    version = _libc.syscall(_SYS_CREATE_RULESET, None, ctypes.c_size_t(0), ctypes.c_uint32(1))
    return max(int(version), 0)


def _fs_rights(abi: int) -> int:
    return _FS_ABI[max(k for k in _FS_ABI if k <= abi)]


def landlock(readable: list[str], abi: int) -> list[str]:
    """Restrict this process to reading (files and directory listings) under ``readable``: no writes, creations,
    deletions, renames or executions anywhere; from ABI 4 no TCP bind or connect; from ABI 6 no signals to
    processes outside this domain and no abstract unix sockets. Returns the walls raised, for the log."""
    if abi < 1:
        raise ConfinementError("Landlock is not available (Linux >= 5.13 with Landlock enabled is needed)")
    attr = _RulesetAttr(_fs_rights(abi), NET_BIND_TCP | NET_CONNECT_TCP if abi >= 4 else 0,
                        SCOPE_ABSTRACT_UNIX_SOCKET | SCOPE_SIGNAL if abi >= 6 else 0)
    size = ctypes.sizeof(_RulesetAttr) if abi >= 6 else (16 if abi >= 4 else 8)
    fd = _check(_libc.syscall(_SYS_CREATE_RULESET, ctypes.byref(attr), ctypes.c_size_t(size), ctypes.c_uint32(0)),
                "landlock_create_ruleset")
    try:
        for path in readable:
            try:
                pfd = os.open(path, os.O_PATH | os.O_CLOEXEC)
            except FileNotFoundError:
                continue
            try:
                rights = FS_READ_FILE | (FS_READ_DIR if os.path.isdir(path) else 0)
                rule = _PathBeneath(rights, pfd)
                _check(_libc.syscall(_SYS_ADD_RULE, fd, _RULE_PATH_BENEATH, ctypes.byref(rule), ctypes.c_uint32(0)),
                       f"landlock_add_rule({path})")
            finally:
                os.close(pfd)
        _check(_libc.prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0), "prctl(PR_SET_NO_NEW_PRIVS)")
        _check(_libc.syscall(_SYS_RESTRICT_SELF, fd, ctypes.c_uint32(0)), "landlock_restrict_self")
    finally:
        os.close(fd)
    walls = ["landlock: files read-only under the Python installation and system libraries"]
    if abi >= 4:
        walls.append("landlock: no TCP bind/connect")
    if abi >= 6:
        walls.append("landlock: no signals to other processes, no abstract unix sockets")
    return walls


# ---------------------------------------------------------------------------------------------- seccomp
DENIED_SYSCALLS = (
    # processes and programs
    "execve", "execveat", "fork", "vfork", "ptrace", "process_vm_readv", "process_vm_writev", "kcmp",
    "pidfd_open", "pidfd_getfd", "pidfd_send_signal", "tkill", "setrlimit", "setpgid", "setsid", "unshare", "setns",
    # the network and other processes' sockets
    "socket", "socketpair", "connect", "bind", "listen", "accept", "accept4",
    # files by handle, bypassing paths; asynchronous I/O that seccomp cannot see into
    "open_by_handle_at", "name_to_handle_at", "io_uring_setup", "io_uring_enter", "io_uring_register",
    "fanotify_init", "inotify_init", "inotify_init1",
    # the kernel's administration
    "mount", "umount2", "move_mount", "fsopen", "fsmount", "fsconfig", "fspick", "open_tree", "mount_setattr",
    "pivot_root", "chroot", "bpf", "perf_event_open", "keyctl", "add_key", "request_key", "userfaultfd",
    "init_module", "finit_module", "delete_module", "kexec_load", "kexec_file_load", "reboot", "swapon", "swapoff",
    "acct", "quotactl", "syslog", "sethostname", "setdomainname", "settimeofday", "clock_settime", "clock_adjtime",
    "adjtimex", "iopl", "ioperm", "personality", "vhangup", "lookup_dcookie", "move_pages", "migrate_pages",
    "process_madvise", "capset", "setuid", "setgid", "setreuid", "setregid", "setresuid", "setresgid", "setfsuid",
    "setfsgid", "setgroups", "mknod", "mknodat", "landlock_create_ruleset", "landlock_add_rule",
)
"""Refused with EPERM (clone3 with ENOSYS, so that glibc falls back to clone, judged by its flags)."""
CLONE_THREAD = 0x00010000


def load_seccomp():
    """The ``pyseccomp`` module (imported before the other walls: finding libseccomp runs ``ldconfig``)."""
    try:
        import pyseccomp
    except (ImportError, RuntimeError, OSError) as exc:  # pyseccomp raises RuntimeError without libseccomp.so
        raise ConfinementError(f"seccomp is not available: {exc} (pyseccomp needs libseccomp.so.2)") from exc
    return pyseccomp


def seccomp(sc, *, settable_limit: int | None = None) -> list[str]:
    """Load the filter: default allow (Landlock covers files), :data:`DENIED_SYSCALLS` fail with EPERM, ``clone``
    only with CLONE_THREAD (threads, no processes), ``kill``, ``tgkill``, ``rt_sigqueueinfo`` and
    ``rt_tgsigqueueinfo`` only to this process, ``prlimit64`` only to read limits. ``sc``: :func:`load_seccomp`.

    ``settable_limit`` (the reward probe's child, which moves its own ``RLIMIT_CPU`` soft limit before each
    candidate): that one resource stays settable by this process on itself (``prlimit64(0, resource, new, ...)``,
    what glibc's ``setrlimit`` makes); within its hard limit, as always for a process without capabilities. The
    worker passes nothing: its filter is unchanged."""
    pid = os.getpid()
    deny = sc.ERRNO(errno.EPERM)
    f = sc.SyscallFilter(sc.ALLOW)
    for name in DENIED_SYSCALLS:
        try:
            f.add_rule(deny, name)
        except (OSError, ValueError, RuntimeError):
            continue  # a syscall this architecture does not have
    f.add_rule(sc.ERRNO(errno.ENOSYS), "clone3")
    f.add_rule(deny, "clone", sc.Arg(0, sc.MASKED_EQ, CLONE_THREAD, 0))
    f.add_rule(deny, "kill", sc.Arg(0, sc.NE, pid))
    f.add_rule(deny, "tgkill", sc.Arg(0, sc.NE, pid))
    # queued signals to another process: Landlock's signal scope (ABI >= 6) refuses them too, older kernels do not
    f.add_rule(deny, "rt_sigqueueinfo", sc.Arg(0, sc.NE, pid))
    f.add_rule(deny, "rt_tgsigqueueinfo", sc.Arg(0, sc.NE, pid))
    if settable_limit is None:
        f.add_rule(deny, "prlimit64", sc.Arg(2, sc.NE, 0))
    else:  # a new limit only for this process (pid 0) and only for that resource
        f.add_rule(deny, "prlimit64", sc.Arg(2, sc.NE, 0), sc.Arg(0, sc.NE, 0))
        f.add_rule(deny, "prlimit64", sc.Arg(2, sc.NE, 0), sc.Arg(1, sc.NE, settable_limit))
    try:
        f.load()
    except OSError as exc:
        raise ConfinementError(f"seccomp_load failed: {exc}") from exc
    return ["seccomp: no exec, fork, sockets, ptrace, mounts, bpf, keys, raised limits or signals to others"]


# ---------------------------------------------------------------------------------------------- all of it
def rlimits(memory_bytes: int = MEMORY_LIMIT_BYTES, cpu_s: int = CPU_LIMIT_S,
            open_files: int = OPEN_FILES_LIMIT) -> list[str]:
    for res, value in ((resource.RLIMIT_AS, memory_bytes), (resource.RLIMIT_CPU, cpu_s), (resource.RLIMIT_FSIZE, 0),
                       (resource.RLIMIT_NOFILE, open_files), (resource.RLIMIT_CORE, 0)):
        hard = resource.getrlimit(res)[1]
        value = value if hard == resource.RLIM_INFINITY else min(value, hard)  # a parent's tighter limit stays
        resource.setrlimit(res, (value, value))
    return [f"rlimits: address space {memory_bytes >> 20} MiB, CPU {cpu_s} s, file size 0, {open_files} files, "
            f"no core"]


def not_dumpable() -> None:
    """``PR_SET_DUMPABLE`` 0: no core dumps, no ptrace attach by the user's other processes (what :func:`confine`
    does first; public for the reward probe's child, which raises its own walls)."""
    _check(_libc.prctl(PR_SET_DUMPABLE, 0, 0, 0, 0), "prctl(PR_SET_DUMPABLE)")


def drop_capabilities() -> None:
    """Clear every capability set (a worker started by root keeps its uid but none of root's powers)."""
    class Header(ctypes.Structure):
        _fields_ = [("version", ctypes.c_uint32), ("pid", ctypes.c_int)]

    class Data(ctypes.Structure):
        _fields_ = [("effective", ctypes.c_uint32), ("permitted", ctypes.c_uint32),
                    ("inheritable", ctypes.c_uint32)]

    data = (Data * 2)()
    _check(_libc.capset(ctypes.byref(Header(0x20080522, 0)), data), "capset")


def readable_roots() -> list[str]:
    """What the worker may read: the Python installation and virtual environment, and the system libraries."""
    roots = {sys.prefix, sys.base_prefix, sys.exec_prefix, sys.base_exec_prefix}
    roots |= {os.path.realpath(r) for r in roots}
    roots |= {"/usr/lib", "/usr/lib64", "/lib", "/lib64", "/usr/local/lib", "/usr/share/zoneinfo"}
    return sorted(roots)


def confine(parent_pid: int, memory_bytes: int = MEMORY_LIMIT_BYTES, cpu_s: int = CPU_LIMIT_S) -> list[str]:
    """Every wall, in order; raises :class:`ConfinementError` when one cannot be raised."""
    sc = load_seccomp()
    die_with_parent(parent_pid)
    _check(_libc.prctl(PR_SET_DUMPABLE, 0, 0, 0, 0), "prctl(PR_SET_DUMPABLE)")
    walls = rlimits(memory_bytes, cpu_s)
    walls += landlock(readable_roots(), landlock_abi())
    if os.geteuid() == 0 or os.getuid() == 0:
        drop_capabilities()  # before the filter, which denies capset
        walls.append("capabilities: none")
    walls += seccomp(sc)
    return walls
