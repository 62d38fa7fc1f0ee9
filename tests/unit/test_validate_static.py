"""Static check of language-model reward code: adversarial sources are rejected with the cause and line named."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

import gendex_envs
from generator.errors import RewardCodeError, UnsafeCodeError
from generator.steps.validate import check_reward_file, check_reward_source

PREVIEW = Path(gendex_envs.__file__).parent / "preview_rewards.py"

HEAD = "import torch\n\n"
EVALUATE = (
    "def evaluate(env):\n"
    "    s = env.spec_success()\n"
    "    return {'fail': torch.zeros_like(s)}\n"
)
REWARD = (
    "def compute_dense_reward(env, obs, action, info):\n"
    "    return torch.zeros(env.num_envs, device=env.device)\n"
)


def module(*parts: str, evaluate: bool = True, reward: bool = True) -> str:
    """A valid module plus ``parts`` (extra top-level code placed after the imports)."""
    return HEAD + "".join(parts) + (EVALUATE if evaluate else "") + (REWARD if reward else "")


def in_reward(body: str) -> str:
    """A module whose compute_dense_reward runs ``body`` (4-space indented lines) first."""
    return HEAD + EVALUATE + "def compute_dense_reward(env, obs, action, info):\n" + body + \
        "    return torch.zeros(env.num_envs, device=env.device)\n"


def rejected(source: str, error: type[RewardCodeError] = UnsafeCodeError) -> str:
    with pytest.raises(RewardCodeError) as info:
        check_reward_source(source, "grasp.py")
    assert type(info.value) is error, f"{type(info.value).__name__}: {info.value}"
    return str(info.value)


# ------------------------------------------------------------------------------------------------ accepted code
def test_shipped_reward_modules_pass(task_version):
    """The preview module and a reference task's; every committed version's are checked by `gendex check` (its
    ``static`` check, tests/sim/test_check.py)."""
    for path in [PREVIEW, *task_version("PutAppleBowl").files.reward_modules()]:
        check_reward_file(path)


def test_idiomatic_reward_code_passes():
    source = '''"""Grasp stage: tips to the mug, thumb opposition."""
from __future__ import annotations

import math

import torch
import torch.nn
import torch.nn.functional as F
from gendex_envs import reward_terms as rt
from gendex_envs.reward_terms import reach
from math import pi
from torch import linalg as LA

REWARD_MAX = 3.0
LIFT_M: float = 0.1
ANGLE = math.pi / 4 + pi
WEIGHTS = (1.0, -2.0, 0.5)


def _dist(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """Batched distance."""
    return LA.norm(a - b, dim=-1)


def evaluate(env):
    h = env.obj_height("mug")
    success = h > LIFT_M
    fail = (h < -0.05) & ~success
    return {"success": success, "fail": fail, "height": h}


def compute_dense_reward(env, obs, action, info, ):
    mug = env.obj_pose("mug").p
    d = _dist(env.palm_pose.p, mug)
    r = reach(d) + rt.lift(info["height"], LIFT_M) + F.relu(torch.cos(torch.full_like(d, ANGLE)))
    total = torch.zeros_like(r)
    for i, w in enumerate(WEIGHTS):
        total = total + w * r * (i + 1)
    if hasattr(env, "goal_pos"):
        total = total + rt.place(mug, getattr(env, "goal_pos"))
    scores = [x.sum() for x in (r, total) if x is not None]
    with torch.no_grad():
        total = torch.where(info["success"], torch.full_like(total, REWARD_MAX), total)
    while True:
        break
    total[total < 0] = 0.0
    return total.clamp(max=REWARD_MAX) + 0 * len(scores) + min(abs(-1), 2) * 0


def _get_obs_extra(env, info):
    return {"palm_to_mug": env.obj_pose("mug").p - env.palm_pose.p}
'''
    check_reward_source(source)


# ------------------------------------------------------------------------------------------------ imports
@pytest.mark.parametrize(("code", "pattern"), [
    ("import os\n", r"line 3: `import os` is not allowed"),
    ("from subprocess import run\n", r"line 3: `from subprocess import \.\.\.` is not allowed"),
    ("import numpy as np\n", r"`import numpy` is not allowed"),
    ("import importlib\n", r"`import importlib`"),
    ("import builtins\n", r"`import builtins`"),
    ("import torch.utils.cpp_extension\n", r"`import torch.utils.cpp_extension` is not allowed"),
    ("from gendex_envs import registry\n", r"`from gendex_envs import registry` is not allowed"),
    ("from torch import load\n", r"`from torch import load` is not allowed: it reads or writes files"),
    ("from torch import hub\n", r"`from torch import hub` is not allowed"),
    ("from math import *\n", r"`from math import \*` is not allowed"),
    ("from . import reward\n", r"relative import"),
    ("from __future__ import braces\n", r"only `from __future__ import annotations`"),
])
def test_imports_outside_the_allow_list_are_rejected(code, pattern):
    assert re.search(pattern, rejected(module(code)))


def test_allow_list_is_named_in_the_message():
    message = rejected(module("import os\n"))
    assert "torch" in message and "math" in message and "gendex_envs.reward_terms" in message


def test_import_inside_a_function_is_rejected():
    assert "imports belong at the top" in rejected(in_reward("    import math\n"))


# ------------------------------------------------------------------------------------------------ names
@pytest.mark.parametrize(("body", "name"), [
    ("    __import__('os').system('ls')\n", "__import__"),
    ("    open('/etc/passwd').read()\n", "open"),
    ("    eval('1 + 1')\n", "eval"),
    ("    exec('x = 1')\n", "exec"),
    ("    compile('1', 'f', 'eval')\n", "compile"),
    ("    g = globals()\n", "globals"),
    ("    v = vars(env)\n", "vars"),
    ("    breakpoint()\n", "breakpoint"),
    ("    print(obs)\n", "print"),
    ("    setattr(env, 'x', 1)\n", "setattr"),
    ("    b = __builtins__\n", "__builtins__"),
])
def test_forbidden_names_are_rejected(body, name):
    message = rejected(in_reward(body))
    assert f"line 7: `{name}` is not allowed" in message, message


def test_forbidden_name_cannot_be_shadowed_either():
    assert "`open` is not allowed" in rejected(in_reward("    open = 1\n"))


def test_builtins_outside_the_allow_list_are_rejected():
    message = rejected(in_reward("    t = type(env)\n"))
    assert "the builtin `type` is not allowed" in message and "allowed builtins:" in message


def test_undefined_name_is_a_reward_code_error():
    message = rejected(in_reward("    x = undefined_thing + 1\n"), RewardCodeError)
    assert "name `undefined_thing` is not defined" in message


# ------------------------------------------------------------------------------------------------ attributes
def test_dunder_escape_chain_is_rejected():
    message = rejected(in_reward("    x = ().__class__.__mro__[1].__subclasses__()\n"))
    for dunder in ("__class__", "__mro__", "__subclasses__"):
        assert f"attribute `.{dunder}`" in message
    assert "line 7" in message


@pytest.mark.parametrize("body", [
    "    d = getattr(env, '__dict__')\n",
    "    d = getattr(env, '_frame')\n",
    "    name = 'reset'\n    d = getattr(env, name)\n",
    "    f = getattr\n",
    "    d = hasattr(torch, 'os')\n",
])
def test_getattr_is_checked_like_an_attribute(body):
    message = rejected(in_reward(body))
    assert "getattr" in message or "hasattr" in message


@pytest.mark.parametrize(("expr", "pattern"), [
    ("torch.load('x')", r"`\.load` in `torch\.load`.*reads or writes files"),
    ("torch.save(obs, 'x')", r"`\.save`"),
    ("torch.hub.load('a', 'b')", r"`\.hub`"),
    ("torch.jit.script", r"`\.jit`"),
    ("torch.compile", r"`\.compile`"),
    ("torch.ops.aten", r"`\.ops`"),
    ("torch.classes", r"`\.classes`"),
    ("torch.utils.cpp_extension.load_inline", r"`\.utils`"),
    ("torch.from_file('x')", r"`\.from_file`"),
    ("torch.os.system('ls')", r"`\.os`.*module"),
    ("torch.sys.modules", r"`\.sys`"),
    ("torch.autograd.grad", r"`torch\.autograd` is the module `torch\.autograd`"),
    ("rt.torch.random.fork_rng", r"`rt\.torch\.random` is the module `torch\.random`"),
    ("torch.manual_seed(0)", r"`\.manual_seed`.*changes the simulator or global state"),
    ("torch.set_default_device('cuda')", r"`\.set_default_device`.*setter"),
    ("env.agent.robot.set_qpos(obs)", r"`\.set_qpos`"),
    ("env.reset()", r"`\.reset`"),
    ("env.task_dir.write_text('x')", r"`\.write_text`"),
    ("env.reward.path.unlink()", r"`\.unlink`"),
    ("env.palm_pose.p.numpy().tofile('x')", r"`\.numpy`"),
    ("env._frame", r"`\._frame`.*private"),
    ("(x for x in obs).gi_frame.f_back", r"`\.gi_frame`"),
    ("'{0.x}'.format(env)", r"`\.format`"),
])
def test_dangerous_attributes_are_rejected(expr, pattern):
    source = in_reward(f"    x = {expr}\n").replace("import torch\n", "import torch\nfrom gendex_envs import "
                                                           "reward_terms as rt\n")
    assert re.search(pattern, rejected(source)), expr


def test_module_may_not_be_aliased_into_a_variable():
    message = rejected(in_reward("    t = torch\n    t.load('x')\n"))
    assert "the module `torch` may only be used as `torch.<name>`" in message


def test_unknown_module_attribute_is_named():
    message = rejected(in_reward("    x = torch.zerosx(3)\n"), RewardCodeError)
    assert "`torch.zerosx` does not exist" in message


def test_attribute_assignment_is_rejected():
    assert "changes an attribute" in rejected(in_reward("    env.reward = None\n"))


# ------------------------------------------------------------------------------------------------ statements
@pytest.mark.parametrize(("code", "pattern"), [
    ("torch.zeros(3)\n", r"line 3: top-level statement `torch\.zeros\(3\)` runs code at import time"),
    ("X = torch.zeros(3)\n", r"line 3: top-level assignment `X = torch\.zeros\(3\)` is not a constant"),
    ("HISTORY = []\n", r"is not a constant"),
    ("if True:\n    X = 1\n", r"top-level statement"),
    ("for i in range(3):\n    pass\n", r"top-level statement"),
    ("try:\n    X = 1\nexcept Exception:\n    pass\n", r"top-level statement"),
    ("class Helper:\n    pass\n", r"class `Helper` is not allowed"),
    ("@torch.no_grad()\ndef helper(x):\n    return x\n", r"decorator on `helper`"),
    ("def helper(x=torch.zeros(3)):\n    return x\n", r"default value `torch\.zeros\(3\)`"),
    ("def helper(x: torch.zeros(3)):\n    return x\n", r"annotation .* must be a plain type"),
    ("X: torch.zeros(10) = 1\n", r"annotation `torch\.zeros\(10\)` must be a plain type"),
    ("async def helper():\n    pass\n", r"async code"),
])
def test_top_level_may_only_define(code, pattern):
    assert re.search(pattern, rejected(module(code))), code


@pytest.mark.parametrize(("body", "pattern"), [
    ("    global X\n", r"global/nonlocal"),
    ("    yield 1\n", r"must return their result, not yield"),
    ("    while True:\n        pass\n", r"line 7: `while True: pass` loops forever"),
    ("    while 1:\n        for i in range(3):\n            break\n", r"loops forever"),
    ("    lam = lambda y=torch.ones(1): y\n", r"default value"),
])
def test_function_bodies_are_restricted(body, pattern):
    assert re.search(pattern, rejected(in_reward(body))), body


def test_while_true_with_break_or_return_is_fine():
    check_reward_source(in_reward("    while True:\n        if obs is None:\n            break\n"))
    check_reward_source(in_reward("    while True:\n        return torch.zeros(env.num_envs)\n"))


# ------------------------------------------------------------------------------------------------ interface
def test_missing_evaluate_is_named():
    message = rejected(module(evaluate=False), RewardCodeError)
    assert "no top-level function `evaluate(env)`" in message


def test_missing_reward_is_named():
    message = rejected(module(reward=False), RewardCodeError)
    assert "`compute_dense_reward(env, obs, action, info)`" in message


@pytest.mark.parametrize(("source", "pattern"), [
    (HEAD + "def evaluate(env, info):\n    return {}\n" + REWARD,
     r"`evaluate` must be defined as `def evaluate\(env\):`"),
    (HEAD + EVALUATE + "def compute_dense_reward(env, obs):\n    return obs\n", r"takes 2 positional"),
    (HEAD + EVALUATE + "def compute_dense_reward(*args):\n    return 0\n", r"\*args"),
    (module("def _get_obs_extra(env):\n    return {}\n"), r"`_get_obs_extra` must be defined as"),
    (module("REWARD_MAX = -1.0\n"), r"REWARD_MAX = -1\.0 must be a finite number > 0"),
    (module("X = 1\nX = 2\n"), r"`X` is bound twice at the top level \(lines 3 and 4\)"),
])
def test_interface_problems_are_named(source, pattern):
    assert re.search(pattern, rejected(source, RewardCodeError))


def test_syntax_error_names_the_line():
    message = rejected(HEAD + "def evaluate(env)\n    return {}\n", RewardCodeError)
    assert message.startswith("grasp.py: syntax error at line 3") and "def evaluate(env)" in message


@pytest.mark.parametrize("source", ["x = 1\x00\n", "x = (" * 300 + "1" + ")" * 300 + "\n", "x = 1\n" * 30000])
def test_unparsable_or_huge_sources_are_rejected(source):
    with pytest.raises(RewardCodeError):
        check_reward_source(source)


def test_deep_expression_does_not_crash_the_checker():
    source = module("X = " + " + ".join(["1"] * 5000) + "\n")
    try:
        check_reward_source(source)
    except RewardCodeError:
        pass


def test_every_problem_is_listed_with_its_line():
    message = rejected("import os\nimport sys\n" + EVALUATE + REWARD)
    assert "(4 problems)" in message  # two imports, and `torch` is then undefined on lines 5 and 7
    assert "- line 1: `import os`" in message and "- line 2: `import sys`" in message


def test_unsafe_wins_over_interface_errors():
    message = rejected("import os\n", UnsafeCodeError)
    assert "`import os`" in message and "no top-level function `evaluate(env)`" in message


# ------------------------------------------------------------------------------------------------ rebuilt check
@pytest.mark.parametrize("body", [
    "    up = torch.zeros_like(env.palm_pose.p)\n    up[:, 2] = 1.0\n",
    "    r = torch.zeros(env.num_envs, device=env.device)\n    r += 0.5 * env.obj_height('mug')\n",
    "    r = env.palm_pose.p * 1.0\n    r[r < 0] = 0.0\n",
    "    p = env.palm_pose.p.clone()\n    p[:, 0] = 0.0\n",
    "    parts = {}\n    parts['reach'] = env.palm_pose.p\n    names = []\n    names.append('reach')\n",
    "    n = 0\n    for t in (env.palm_pose.p, env.tip_positions):\n        n += 1\n",
    "    f = lambda x, k=2: x * k\n    s = f'{env.num_envs}: {f(2)}'\n",
    "    type_ = 1\n    with torch.no_grad():\n        z = [x * type_ for x in (1, 2)]\n",
])
def test_code_that_writes_only_what_it_created_passes(body):
    check_reward_source(in_reward(body))


def test_a_builtin_bound_in_a_function_is_usable_there_only():
    source = HEAD + "def _helper(x):\n    type = abs\n    return type(x)\n\n" + EVALUATE + REWARD
    check_reward_source(source)
    message = rejected(source.replace("return {'fail'", "t = type(s)\n    return {'fail'"))
    assert "the builtin `type` is not allowed in reward code (in `evaluate`)" in message


@pytest.mark.parametrize(("body", "pattern"), [
    ("    match obs:\n        case {'a': x}:\n            pass\n", r"\(Match\)"),
    ("    p = env.palm_pose.p\n    p[:, 0] = 0.0\n", r"which this function did not create"),
    ("    p = env.palm_pose.p\n    p += 1.0\n", r"may change `p` in place"),
    ("    info['success'] = info['success'] | True\n", r"which this function did not create"),
    ("    env.palm_pose.p.mul_(0)\n", r"in-place method"),
    ("    torch.mul(obs, 2, out=obs)\n", r"keyword `out=`"),
    ("    s = 'a__b'\n", r"contains `__`"),
])
def test_rebuilt_rules_name_the_reason(body, pattern):
    assert re.search(pattern, rejected(in_reward(body))), body
