"""GenDex runtime: the UR10e+ShadowHand agent, the asset catalog, task versions, the generic task env and the registry.

Importing this package registers every task version under ``generated_tasks/`` (and ``$GENDEX_TASKS_PATH``) with
Gymnasium, so ``import gendex_envs; gym.make("GenDex/PutAppleBowl-v0")`` works. Heavy modules (sapien, ManiSkill)
load only when an env is made. Applications (solving, data, training, the generator) live above this package and
reach it only through its public API.
"""

from gendex_envs.blas import pin_kernels

pin_kernels()  # before anything below loads numpy

from gendex_envs.registry import make_env, make_task_env, register_tasks, registered_tasks, resolve_task  # noqa: E402
from gendex_envs.task_version import TaskVersion  # noqa: E402

__all__ = ["TaskVersion", "make_env", "make_task_env", "register_tasks", "registered_tasks", "resolve_task"]
__version__ = "0.1.0"

register_tasks()
