"""GenDex runtime: the UR10e+ShadowHand agent, the asset catalog, the generic task env and the task registry.

Importing this package registers every task under ``generated_tasks/`` (and ``$GENDEX_TASKS_PATH``) with Gymnasium,
so ``import gendex_envs; gym.make("GenDex/PutAppleBowl-v0")`` works. Heavy modules (sapien, ManiSkill) load only when
an env is made.
"""

from gendex_envs.registry import make_task_env, register_tasks, registered_tasks

__all__ = ["make_task_env", "register_tasks", "registered_tasks"]
__version__ = "0.1.0"

register_tasks()
