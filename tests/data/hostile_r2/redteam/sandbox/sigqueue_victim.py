# expect: no signal reaches another process, whichever syscall sends it (first wall down)
# kill, tkill, tgkill and pidfd_send_signal are in the seccomp filter; rt_sigqueueinfo (what sigqueue(3) uses) and
# rt_tgsigqueueinfo are not. Only Landlock's signal scope (ABI 6, Linux 6.12) stops them; on an older kernel the
# worker could send SIGKILL to its parent.
import ctypes
import os
import signal

import torch

NR_RT_SIGQUEUEINFO = 129  # x86_64


def evaluate(env):
    libc = ctypes.CDLL(None, use_errno=True)
    info = (ctypes.c_int * 32)()
    info[0] = signal.SIGTERM  # si_signo
    info[2] = -1  # si_code SI_QUEUE: the code other processes may send
    info[4] = os.getpid()  # si_pid
    if libc.syscall(NR_RT_SIGQUEUEINFO, {victim}, signal.SIGTERM, ctypes.byref(info)) != 0:
        raise PermissionError(ctypes.get_errno(), "rt_sigqueueinfo refused")
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)}


def compute_dense_reward(env, obs, action, info):
    return torch.zeros(env.num_envs, device=env.device)
