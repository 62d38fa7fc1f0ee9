"""PPO presets: the paper preset is the seed paper's table; bad names and settings are named errors."""

import pytest

from gendex.train.presets import PRESETS, TrainingError, get_preset, parse_overrides


def test_paper_preset_matches_the_seed_table():
    p = get_preset("paper")
    assert (p.n_envs, p.learning_rate, p.gamma, p.gae_lambda, p.n_epochs, p.clip_range, p.ent_coef, p.vf_coef) == \
        (1024, 3e-4, 0.998, 0.95, 4, 0.2, 0.01, 0.75)
    assert p.net_arch == (1024, 1024, 512)
    kw = p.ppo_kwargs()
    assert kw["policy_kwargs"]["net_arch"] == [1024, 1024, 512]
    assert kw["policy_kwargs"]["activation_fn"].__name__ == "ReLU"


def test_cpu_preset_fits_two_cores():
    p = PRESETS["cpu"]
    assert p.n_envs == 2 and not p.gpu_backend and p.batch_size <= p.n_steps * p.n_envs


def test_errors_name_the_options():
    with pytest.raises(TrainingError, match="presets: \\['cpu', 'paper'\\]"):
        get_preset("gpu")
    with pytest.raises(TrainingError, match="unknown PPO settings \\['lr'\\]"):
        get_preset("cpu").with_overrides(lr=1e-3)


def test_overrides_from_the_command_line_are_typed_like_the_preset():
    got = parse_overrides(["log_std_init=-1.2", "n_steps=256", "net_arch=128,64", "gpu_backend=false"])
    assert got == {"log_std_init": -1.2, "n_steps": 256, "net_arch": (128, 64), "gpu_backend": False}
    p = get_preset("cpu").with_overrides(**got)
    assert p.log_std_init == -1.2 and p.ppo_kwargs()["policy_kwargs"]["net_arch"] == [128, 64]
    with pytest.raises(TrainingError, match="KEY=VALUE"):
        parse_overrides(["log_std_init"])
    with pytest.raises(TrainingError, match="unknown PPO setting 'lr'"):
        parse_overrides(["lr=1e-3"])
    with pytest.raises(TrainingError, match="n_steps: '2.5' is not a int"):
        parse_overrides(["n_steps=2.5"])
