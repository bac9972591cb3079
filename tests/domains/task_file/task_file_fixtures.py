"""A small task file for the task-file tests, and custom perturbations they load by `module:function`."""

from __future__ import annotations

from pathlib import Path

CUPS = """\
version: 1
name: cups
workspace:
  units: m
  bounds: {x: [0, 1], y: [-0.5, 0.5]}
  min_spacing: 0.1
  regions:
    left: {x: [0.2, 0.8], y: [0.3, 0.5]}
    right: {x: [0.2, 0.8], y: [-0.5, -0.3]}
    middle: {x: [0.2, 0.8], y: [-0.2, 0.2]}
objects:
  red_cup: {colour: red, category: cup, area: middle}
  blue_cup: {colour: blue, category: cup, area: middle}
  green_cup: {colour: green, category: cup, area: middle, spare: true}
templates:
  - name: move
    text: "move the {cup} to the {side}"
    slots: {cup: {category: cup}, side: [left, right]}
    goal: {subject: "{cup}", in: "{side}"}
perturbations:
  - {name: L, kind: paraphrase, synonyms: [[move, push]]}
  - {name: LB, kind: flip, pairs: [[left, right]]}
  - {name: S, kind: move_distractor}
  - {name: SB, kind: move_goal_object}
"""

# Two listed instances of the cups task (appended in place of its sampler).
LISTED = """\
instances:
  - template: move
    slots: {cup: red_cup, side: left}
    placements: {red_cup: [0.5, 0.0], blue_cup: [0.5, 0.15]}
  - instruction: put the blue cup on the right
    family: by_hand
    goal: {subject: blue_cup, in: right}
    placements: {red_cup: [0.4, 0.0], blue_cup: [0.6, 0.1]}
"""


def write(tmp_path: Path, text: str, name: str = "cups.yaml") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def louder(instance, rng, suffix):
    """ΔL: the same instruction, said with a suffix (a custom perturbation with a parameter)."""
    return instance.derive(instruction=instance.instruction + suffix)


def other_cup(instance, rng, task):
    """ΔLB: ask for the other cup on the table (a custom perturbation that uses the task to re-word)."""
    others = [n for n in instance.scene.objects if n.endswith("_cup") and n != instance.goal["slots"]["cup"]]
    return task.compose(instance, slots={"cup": others[0]}) if others else None
