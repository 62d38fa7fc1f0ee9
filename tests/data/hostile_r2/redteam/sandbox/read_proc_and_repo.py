# expect: PermissionError for each read (first wall down): Landlock lets the worker read only the Python installation
# Another process's environment (tokens), the worker's own, the repository's git config and the user's home.
import torch

PATHS = ("/proc/{victim}/environ", "/proc/self/environ", "/proc/self/cmdline", "{repo}/.git/config",
         "{repo}/pyproject.toml", "/root/.bash_history", "/etc/hostname")


def evaluate(env):
    leaked = []
    for path in PATHS:
        try:
            with open(path, "rb") as f:
                leaked.append(path + ": " + f.read(200).decode("latin-1"))
        except OSError:
            pass
    if leaked:
        raise ValueError("LEAKED " + " | ".join(leaked))
    raise PermissionError("every read was refused")


def compute_dense_reward(env, obs, action, info):
    return torch.zeros(env.num_envs, device=env.device)
