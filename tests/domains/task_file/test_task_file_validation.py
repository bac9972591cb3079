"""Every task-file mistake is reported in one line naming the file, the line and key, and what is expected."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.domains import load_task
from lerobot_contrast.domains.task_file import TaskFileError, load_task_file, task_from_dict
from tests.domains.task_file.task_file_fixtures import CUPS, LISTED, write

# (replacements applied to CUPS, text on the line the error must name, expected message fragment)
CASES = {
    "missing version": ([("version: 1\n", "")], "name: cups", "top level: missing key 'version'"),
    "bad version": ([("version: 1", "version: 2")], "version: 2", "version: unsupported format version 2"),
    "unknown top-level key": (
        [("name: cups", "name: cups\ncolours: []")],
        "colours: []",
        "colours: unknown key 'colours'",
    ),
    "misspelt attribute": (
        [("red_cup: {colour: red", "red_cup: {color: red")],
        "red_cup: {color",
        "objects.red_cup.color: unknown key 'color'; did you mean 'colour'?",
    ),
    "invalid YAML": ([("y: [-0.5, 0.5]}", "y: [-0.5, 0.5]")], None, "invalid YAML"),
    "key given twice": ([("name: cups", "name: cups\nname: mugs")], "name: mugs", "key 'name' is given twice"),
    "missing workspace": (
        [("workspace:\n  units: m", "space:\n  units: m")],
        "space:",
        "unknown key 'space'; did you mean 'workspace'?",
    ),
    "unknown units": ([("units: m", "units: ft")], "units: ft", "workspace.units: expected one of: m, cm, mm"),
    "reversed bounds": (
        [("x: [0, 1], y", "x: [1, 0], y")],
        "bounds:",
        "workspace.bounds.x: expected [min, max] with min < max",
    ),
    "region outside the workspace": (
        [("y: [0.3, 0.5]}", "y: [0.3, 0.7]}")],
        "left: {x",
        "workspace.regions.left: region 'left' reaches outside the workspace",
    ),
    "tray over a region": (
        [
            (
                "    middle: {x: [0.2, 0.8], y: [-0.2, 0.2]}\n",
                "    middle: {x: [0.2, 0.8], y: [-0.2, 0.2]}\n  tray: {x: [0.7, 1.0], y: [0.3, 0.4]}\n",
            )
        ],
        "tray:",
        "workspace.tray: the tray overlaps region 'left'",
    ),
    "tray as a disc": (
        [
            (
                "    middle: {x: [0.2, 0.8], y: [-0.2, 0.2]}\n",
                "    middle: {x: [0.2, 0.8], y: [-0.2, 0.2]}\n  tray: {center: [0.9, 0], radius: 0.05}\n",
            )
        ],
        "tray:",
        "workspace.tray: the tray is a box",
    ),
    "object that may be placed in the tray": (
        [
            (
                "    middle: {x: [0.2, 0.8], y: [-0.2, 0.2]}\n",
                "    middle: {x: [0.2, 0.8], y: [-0.2, 0.2]}\n  tray: {x: [0.85, 1.0], y: [-0.1, 0.1]}\n",
            ),
            ("area: middle, spare", "spare"),
        ],
        "green_cup:",
        "'green_cup' may be placed in the tray (the whole workspace overlaps it); give it an area apart from the tray",
    ),
    "ambiguous object words": (
        [("blue_cup: {colour: blue", "blue_cup: {colour: red")],
        "blue_cup:",
        "objects 'red_cup' and 'blue_cup' are both called 'red cup'",
    ),
    "movable object with a fixed place": (
        [("area: middle}\n  blue", "area: middle, at: [0.5, 0]}\n  blue")],
        "red_cup:",
        "objects.red_cup.at: only fixed objects (movable: false) have a fixed place",
    ),
    "unknown object in a template slot": (
        [("{cup: {category: cup}", "{cup: [red_cup, purple_cup]")],
        "slots:",
        "templates[0].slots.cup[1]: unknown object or region 'purple_cup'",
    ),
    "undeclared slot in a template text": (
        [('to the {side}"', 'to the {place}"')],
        "text:",
        "templates[0].text: {place} in 'move the {cup} to the {place}' is not declared under slots",
    ),
    "goal names an unknown slot": (
        [('in: "{side}"', 'in: "{where}"')],
        "goal:",
        "templates[0].goal.in: {where} is not a slot of this template",
    ),
    "near without a distance": (
        [('in: "{side}"}', "near: red_cup}")],
        "goal:",
        "templates[0].goal: missing key 'within'",
    ),
    "predicate outcome without a goal": (
        [('    goal: {subject: "{cup}", in: "{side}"}\n', "")],
        "- name: move",
        "templates[0]: outcome mode is predicate but 'move' has no `goal:`",
    ),
    "subgoals outcome without subgoals": (
        [("templates:", "outcome: {mode: subgoals}\ntemplates:")],
        "- name: move",
        "outcome mode is subgoals but 'move' has no `subgoals:`",
    ),
    "objects do not fit": (
        [("min_spacing: 0.1", "min_spacing: 0.9")],
        "min_spacing: 0.9",
        "workspace.min_spacing: cannot place the 2 movable objects 0.9 m apart",
    ),
    "template that is always achieved": (
        [
            (
                "area: middle}\n  blue_cup: {colour: blue, category: cup, area: middle}",
                "area: left}\n  blue_cup: {colour: blue, category: cup, area: left}",
            ),
            ("side: [left, right]", "side: [left]"),
            ("{name: LB, kind: flip, pairs: [[left, right]]}", "{name: LB, kind: change_goal}"),
        ],
        "- name: move",
        "template 'move' never gives a valid instance",
    ),
    "unknown perturbation kind": (
        [("kind: flip", "kind: mirror")],
        "name: LB",
        "perturbations[1].kind: expected one of: paraphrase, swap_referents, flip",
    ),
    "flip that can never apply": (
        [("pairs: [[left, right]]", "pairs: [[left, middle]]")],
        "name: LB",
        "perturbations[1]: perturbation 'LB' (flip) can never apply: no template slot can take both names",
    ),
    "swap that can never apply": (
        [("kind: flip, pairs: [[left, right]]", "kind: swap_referents")],
        "name: LB",
        "(swap_referents) can never apply: no template has two slots of the same kind",
    ),
    "paraphrase that can never apply": (
        [("[[move, push]]", "[[carry, bring]]")],
        "name: L,",
        "(paraphrase) can never apply: no synonym occurs in an instruction",
    ),
    "phrase in two synonym groups": (
        [("[[move, push]]", "[[move, push], [shove, push]]")],
        "name: L,",
        "perturbations[0].synonyms[1]: 'push' is in two synonym groups",
    ),
    "duplicate perturbation name": (
        [("{name: S, kind", "{name: L, kind")],
        "name: L, kind: move_distractor",
        "perturbation 'L' is declared twice",
    ),
    "custom function in a module that is nowhere": (
        [("{name: SB, kind: move_goal_object}", "{name: SB, axis: SB, function: 'nowhere_at_all:fn'}")],
        "name: SB",
        "perturbations[3].function: cannot import 'nowhere_at_all'",
    ),
    "custom function that is not there": (
        [
            (
                "{name: SB, kind: move_goal_object}",
                "{name: SB, axis: SB, function: 'tests.domains.task_file.task_file_fixtures:nope'}",
            )
        ],
        "name: SB",
        "module 'tests.domains.task_file.task_file_fixtures' has no function 'nope'",
    ),
    "custom function without its params": (
        [
            (
                "{name: SB, kind: move_goal_object}",
                "{name: SB, axis: L, function: 'tests.domains.task_file.task_file_fixtures:louder'}",
            )
        ],
        "name: SB",
        "louder() must accept (instance, rng, **params)",
    ),
    "custom function without an axis": (
        [
            (
                "{name: SB, kind: move_goal_object}",
                "{name: SB, function: 'tests.domains.task_file.task_file_fixtures:louder'}",
            )
        ],
        "name: SB",
        "perturbations[3]: missing key 'axis'",
    ),
    "listed placement outside the workspace": (
        [("{red_cup: [0.5, 0.0], blue_cup", "{red_cup: [1.5, 0.0], blue_cup")],
        "{red_cup: [1.5",
        "instances[0].placements.red_cup: 'red_cup' is placed outside the workspace bounds",
    ),
    "listed slot value not allowed": (
        [("{cup: red_cup, side: left}", "{cup: red_cup, side: middle}")],
        "slots: {cup: red_cup, side: middle}",
        "instances[0].slots.side: 'middle' is not allowed in slot 'side'; expected one of: left, right",
    ),
    "listed goal already achieved": (
        [("blue_cup: [0.6, 0.1]}", "blue_cup: [0.6, -0.4]}")],
        "- instruction",
        "instances[1]: the goal already holds in these placements",
    ),
    "listed unknown template": (
        [("- template: move", "- template: carry")],
        "- template: carry",
        "instances[0].template: unknown template 'carry'; declared templates: move",
    ),
    "listed and sampled": ([("instances:", "sampler: {seed: 1}\ninstances:")], "sampler:", "give either `instances:`"),
    "sampler fixes an unknown slot": (
        [("perturbations:", "sampler: {slots: {mug: red_cup}}\nperturbations:")],
        "sampler:",
        "sampler.slots.mug: no template has a slot 'mug'; slots: cup, side",
    ),
    "sampler fixes a value the slot does not take": (
        [("perturbations:", "sampler: {slots: {side: middle}}\nperturbations:")],
        "sampler:",
        "sampler.slots.side: 'middle' is not allowed in slot 'side'; expected one of: left, right",
    ),
}


def _apply(replacements, listed: bool) -> str:
    text = CUPS + (LISTED if listed else "")
    for old, new in replacements:
        assert old in text, old
        text = text.replace(old, new, 1)
    return text


@pytest.mark.parametrize("case", sorted(CASES))
def test_each_mistake_gets_one_line_naming_file_line_key_and_what_is_expected(case, tmp_path):
    replacements, marker, message = CASES[case]
    text = _apply(replacements, listed="listed" in case)
    path = write(tmp_path, text)
    with pytest.raises(TaskFileError) as raised:
        load_task_file(path)
    error = str(raised.value)
    assert "\n" not in error and message in error, error
    lines = [i for i, line in enumerate(text.splitlines(), 1) if marker is not None and marker in line]
    if lines:
        assert error.startswith(f"{path}:{lines[0]}: "), error
    else:
        assert error.startswith(f"{path}:"), error


def test_the_base_file_and_its_listed_variant_are_valid(tmp_path):
    assert [p.name for p in load_task_file(write(tmp_path, CUPS)).perturbations] == ["L", "LB", "S", "SB"]
    listed = load_task_file(write(tmp_path, CUPS + LISTED))
    assert [i.instruction for i in listed.sample(2, np.random.default_rng(0))] == [
        "move the red cup to the left",
        "put the blue cup on the right",
    ]


def test_asking_for_more_listed_instances_than_the_file_lists_is_refused(tmp_path):
    task = load_task_file(write(tmp_path, CUPS + LISTED))
    with pytest.raises(UserError, match=r"--n_instances=3: .*cups.yaml lists 2 instances; ask for at most 2"):
        task.sample(3, np.random.default_rng(0))


def test_errors_from_python_data_name_the_key_without_a_line():
    import yaml

    data = yaml.safe_load(CUPS.replace("units: m", "units: ft"))
    with pytest.raises(TaskFileError, match=r"^<task>: workspace.units: expected one of: m, cm, mm; got 'ft'$"):
        task_from_dict(data)


@pytest.mark.parametrize(
    ("name", "message"),
    [
        (
            "nope",
            "--task: unknown task 'nope'; choose from: language_table, libero_10, libero_goal, libero_object, libero_spatial, vln, vln_paper, lekiwi_fetch, so101_blocks",
        ),
        ("missing/task.yaml", "--task: no task file at missing/task.yaml"),
    ],
)
def test_unknown_tasks_are_named(name, message):
    with pytest.raises(UserError, match=message):
        load_task(name)


def test_unknown_families_are_named():
    with pytest.raises(UserError, match=r"--families: unknown families \['stack'\] for task 'so101_blocks'"):
        load_task("so101_blocks", families=["stack"])


def test_the_cli_prints_a_bad_task_file_as_one_error_line(tmp_path):
    path = write(tmp_path, CUPS.replace("y: [0.3, 0.5]}", "y: [0.3, 0.7]}"))
    result = subprocess.run(
        [sys.executable, "-m", "lerobot_contrast.eval", f"--task={path}", "--dry_run=true"],
        capture_output=True,
        text=True,
    )
    assert result.returncode == 2 and "Traceback" not in result.stderr
    assert (
        result.stderr == f"error: {path}:8: workspace.regions.left: region 'left' reaches outside the workspace "
        "(x 0..1, y -0.5..0.5 m); move or shrink it\n"
    )


def test_deleting_any_line_gives_a_valid_task_or_a_one_line_error(tmp_path):
    text = CUPS + LISTED
    lines = text.splitlines(keepends=True)
    outcomes = set()
    for i in range(len(lines)):
        path = write(tmp_path, "".join(lines[:i] + lines[i + 1 :]))
        try:
            load_task_file(path)
            outcomes.add("valid")
        except TaskFileError as error:
            assert "\n" not in str(error) and str(error).startswith(f"{path}:")
            outcomes.add("error")
    assert outcomes == {"valid", "error"}


def test_instances_built_in_python_are_checked_against_the_template(tmp_path):
    task = load_task_file(write(tmp_path, CUPS))
    scene = task.storage_scene()
    with pytest.raises(UserError, match=r"task 'cups' has no template 'carry'; it has: move"):
        task.make_instance("x", "carry", {}, scene)
    with pytest.raises(UserError, match=r"slot 'side' needs one of left, right, got 'up'"):
        task.make_instance("x", "move", {"cup": "red_cup", "side": "up"}, scene)


def test_sampler_slots_fix_every_base_and_leave_the_perturbations_free(tmp_path):
    task = load_task_file(
        write(
            tmp_path,
            CUPS.replace("perturbations:", "sampler: {seed: 3, slots: {cup: red_cup, side: left}}\nperturbations:"),
        )
    )
    bases = task.sample(20, np.random.default_rng(0))
    assert {b.instruction for b in bases} == {"move the red cup to the left"}
    assert len({b.scene.objects["red_cup"].y for b in bases}) == 20  # new placements each time
    flipped = task.perturbations.get("LB").apply(bases[0], np.random.default_rng(0))
    assert flipped.instruction == "move the red cup to the right"
