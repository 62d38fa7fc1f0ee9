"""The static check of reward code (:mod:`gendex_envs.code_check.checker`; rules in
:mod:`gendex_envs.code_check.rules`). It lives in the runtime because untrusted task folders are checked when they
are loaded, not only when the generator writes them (:func:`gendex_envs.reward_module.load_reward_module`)."""

from gendex_envs.code_check.checker import check_reward_file, check_reward_source

__all__ = ["check_reward_file", "check_reward_source"]
