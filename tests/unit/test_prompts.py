"""Prompt templates render with strict variables; the manifest matches the templates."""

from __future__ import annotations

import pytest

from generator.errors import PromptError
from generator.prompts import PROMPTS_DIR, load_manifest, render, template


def test_manifest_lists_every_template_with_the_variables_it_uses():
    manifest = load_manifest()
    files = {p.name for p in PROMPTS_DIR.glob("*.txt")}
    assert files == {t.file.name for t in manifest.values()}
    # the required prompts all exist
    for name in ("propose", "propose_guided", "scene", "scene_analysis", "env_api", "patterns",
                 "function_generation", "substage", "previous_function", "previous_stage"):
        assert name in manifest
    assert template("propose").temperature == 1.2
    assert template("scene").temperature == 0.3


def test_missing_variable_is_an_error_naming_it():
    with pytest.raises(PromptError, match=r"missing variables \['content'\]"):
        render("previous_stage", source_type="x")


def test_unexpected_variable_is_an_error_naming_it():
    with pytest.raises(PromptError, match=r"unexpected variables \['colour'\]"):
        render("previous_stage", source_type="x", content="y", colour="red")


def test_unknown_template_lists_the_known_ones():
    with pytest.raises(PromptError, match="propose_guided"):
        render("proposal_v2")


def test_manifest_that_disagrees_with_its_template_is_rejected(tmp_path):
    (tmp_path / "a.txt").write_text("Hello {{ who }} and {{ other }}")
    (tmp_path / "manifest.yaml").write_text("a:\n  file: a.txt\n  variables: [who]\n")
    with pytest.raises(PromptError, match=r"uses \['other', 'who'\] but the manifest declares \['who'\]"):
        load_manifest(tmp_path)


def test_rendered_guided_prompt_carries_the_instruction_the_skills_the_reading_and_the_library():
    from generator.catalog_view import asset_dicts
    from generator.instruction import read_instruction, skill_vocabulary

    reading = "\n".join(read_instruction("grab the apple", asset_dicts()).lines())
    text = render("propose_guided", instruction="grab the apple", asset_guidance="- apple | apple",
                  existing_tasks="- (none)", skills="  - reach: ...", condition_types="lifted",
                  control_joints="arm, hand", task_skills=skill_vocabulary(), reading=reading)
    assert '"grab the apple"' in text and "- apple | apple" in text and "{{" not in text
    assert "'apple' is apple" in text  # the reading
    assert "close: close, shut" in text and "turn on the faucet" in text  # the vocabulary of every task skill


def test_the_guided_prompt_describes_parts_in_turn_towers_and_take_outs():
    """The Claude backend is told the task language the offline author writes: a reading of several steps is one
    task with an 'also' list, a tower is two stacks, a take-out starts its object in the container."""
    from generator.catalog_view import asset_dicts
    from generator.instruction import read_instruction, skill_vocabulary

    request = "take the can out of the bowl, then put the lemon and the plum in the large bowl"
    reading = read_instruction(request, asset_dicts())
    assert [r.skill for r in (reading, *reading.then)] == ["take_out", "put_in", "put_in"]
    text = render("propose_guided", instruction=request, asset_guidance="-", existing_tasks="- (none)",
                  skills="-", condition_types="placed, inside", control_joints="arm, hand",
                  task_skills=skill_vocabulary(), reading="\n".join(reading.lines()))
    assert '"starts_in": "<the container\'s name>"' in text and '"also" list' in text
    assert 'then "put the lemon in the large bowl"' in text and "take_out" in text
    assert "tower" in text and "a lifted object only in the last part" in text


def test_the_prompts_describe_a_drawer_as_a_receptacle_with_its_joint():
    """*Put the can in the bottom drawer*: an ``inside`` condition naming the drawer's joint, in the form
    ``parse_proposal`` accepts (tests/unit/test_drawers.py); both proposal prompts say so."""
    guided = render("propose_guided", instruction="put the can in the drawer", asset_guidance="-",
                    existing_tasks="- (none)", skills="-", condition_types="inside", control_joints="arm, hand",
                    task_skills="-", reading="-")
    assert "drawer's joint" in " ".join(guided.split())
    assert "min_gap_m, max_gap_m, joint}" in guided and "lowest drawer" in guided
    free = render("propose", asset_guidance="-", existing_tasks="- (none)", skills="-", condition_types="inside",
                  control_joints="arm, hand")
    assert '"joint": "drawer_1_slide"' in " ".join(free.split())


def test_the_guided_prompt_describes_a_group_of_objects():
    """*Put all the fruit in the pot*: the Claude backend sees the objects the reader drew (each marked with the
    group) and is told to use them, say the command as the person did and keep other fruit off the table."""
    from generator.catalog_view import asset_dicts
    from generator.instruction import read_instruction, skill_vocabulary

    request = "put all the fruit in the large bowl"
    reading = read_instruction(request, asset_dicts())
    drawn = [r.objects[0].asset for r in (reading, *reading.then)]
    text = render("propose_guided", instruction=request, asset_guidance="-", existing_tasks="- (none)",
                  skills="-", condition_types="inside", control_joints="arm, hand",
                  task_skills=skill_vocabulary(), reading="\n".join(reading.lines()))
    flat = " ".join(text.split())
    assert all(f"chose {a}" in text for a in drawn) and "'all the fruit' is read as" in text
    assert "use exactly the objects the reading drew" in flat and "no other object of that kind" in flat


def test_the_scene_prompt_offers_every_scene_style_and_its_reference_names_one():
    """A Claude scene answer may name a style (`scene: {style: ...}`): the prompt lists every style but plain, and the
    reference file it copies has a scene section that parses."""
    import yaml

    from gendex_envs.scene_styles import DEFAULT_STYLE, STYLES
    from gendex_envs.spec import parse_task_spec
    from generator.steps.scene import scene_styles

    text = render("scene", proposal_json="{}", reference_yaml="-", asset_guidance="-", table_size_m=[1.6, 1.2],
                  robot_base_m=[-0.8, 0, 0], reach_m=1.25, scale_range=[0.3, 2.0], candidate_index=1,
                  hand_span_m=0.12, scene_styles=scene_styles())
    assert "`scene: {style: ...}`" in text
    assert all(name in text for name in STYLES if name != DEFAULT_STYLE) and DEFAULT_STYLE not in scene_styles()
    spec = parse_task_spec(yaml.safe_load((PROMPTS_DIR / "reference_spec.yaml").read_text()))
    assert spec.scene is not None and spec.scene.style in STYLES
