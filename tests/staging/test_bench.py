"""The staging bench on the tabletop simulator: overlays on the camera view, the colour check that catches a block
placed off target, what the journal records of it, and resuming a run stopped mid-staging."""

import dataclasses
import io
import json
import urllib.request

import cv2
import numpy as np
import pytest
import rerun as rr
from rerun.experimental import RrdReader
from rich.console import Console

from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.domains.language_table import board as tabletop
from lerobot_contrast.domains.language_table.config_language_table_sim import LanguageTableSimConfig
from lerobot_contrast.domains.language_table.language_table_sim import LanguageTableSim
from lerobot_contrast.domains.language_table.render import TabletopRenderer
from lerobot_contrast.domains.task_file.loader import load_task_file
from lerobot_contrast.eval import equipped, planned_evaluation
from lerobot_contrast.operators.base import SessionStopped
from lerobot_contrast.operators.console import Answers, OperatorConsole
from lerobot_contrast.operators.person_page import PersonPage
from lerobot_contrast.policies import make_policy
from lerobot_contrast.spine.config import EvalConfig
from lerobot_contrast.spine.evaluation import run
from lerobot_contrast.spine.flags import parse_config
from lerobot_contrast.staging import homography, locate, overlay
from lerobot_contrast.staging.check import MEMORY, Bench
from lerobot_contrast.staging.setup import geometry
from tests.staging.sim_camera import WHERE, board_frame

CUBE = tabletop.SHAPE_FOOTPRINT["cube"][0]
OFF = 0.05  # the clumsy operator's slip: 5 cm to the robot's left


@pytest.fixture(scope="module")
def calibration():
    return homography.fit("top", board_frame(TabletopRenderer()), WHERE, 1.0, ((0.15, -0.25), (0.45, 0.25)))


class Hands(LanguageTableSim):
    """The simulated table, staged by an operator who follows a script: "slip" puts red_cube 5 cm off its target,
    "exact" places everything as asked, "none" leaves the table as it is (after a restart, it was staged already)."""

    def __init__(self, script: list[str]) -> None:
        super().__init__(LanguageTableSimConfig(camera=True))
        self.script = script

    def stage_scene(self, scene: Scene) -> None:
        action = self.script.pop(0) if self.script else "exact"
        if action == "slip":
            red = scene.objects["red_cube"]
            scene = scene.with_object("red_cube", Pose(red.x, red.y + OFF, red.yaw))
        if action != "none":
            super().stage_scene(scene)


def evaluation(run_dir, calibration, robot, answers, *flags, recording=None, console_class=OperatorConsole):
    cfg = parse_config(
        EvalConfig,
        ["--task=so101_blocks", "--robot.type=language_table_sim", "--operator=console", "--n_instances=1",
         "--perturbations=[S1]", "--policy.type=random", "--max_episode_steps=2", "--rerun=false", f"--output_dir={run_dir}", *flags],
    )  # fmt: skip
    planned = planned_evaluation(cfg)
    bench = Bench(
        calibration, geometry(planned.task, CUBE), planned.task.cost_model("distance"), tolerance=0.02,
        measured_cost=cfg.cost == "measured", recording=recording, run_dir=lambda: run_dir,
    )  # fmt: skip
    console = console_class(Answers(io.StringIO("".join(a + "\n" for a in answers))), Console(file=io.StringIO()))
    console.bench = bench
    policy = make_policy(cfg.policy, robot, planned.task, {})
    return dataclasses.replace(equipped(cfg, planned, robot, policy, console), verbose=False)


def journal(run_dir):
    return [json.loads(line) for line in (run_dir / "journal.jsonl").read_text().splitlines()]


@pytest.fixture
def robot():
    robot = Hands([])
    robot.connect()
    yield robot
    robot.disconnect()


def test_target_outlines_land_on_the_rendered_blocks(calibration):
    target = Scene({"red_cube": Pose(0.30, 0.10, 0.3), "green_cube": Pose(0.25, -0.10), "blue_cube": Pose(0.40, 0.0)})
    believed = Scene({name: Pose(0.20, 0.20) for name in target.objects})
    frame = TabletopRenderer().render(target, (0.2, 0.0))
    inside = locate.workspace_mask(calibration, ((0.15, -0.25), (0.45, 0.25)))
    for mark in overlay.marks(calibration, believed, target, CUBE):
        outline = np.zeros(frame.shape[:2], np.uint8)
        cv2.fillPoly(outline, [np.round(mark.outline).astype(np.int32)], 1)
        block = (locate.colour_mask(frame, mark.name.split("_")[0]) & inside) > 0
        assert block[outline > 0].mean() > 0.8, mark.name  # the outline sits on the block's own pixels
        assert mark.state == "move" and mark.label.startswith(mark.name)
        assert np.linalg.norm(mark.start - calibration.to_pixels(np.array([[0.20, 0.20]]))[0]) < 1e-6
    assert overlay.draw(frame, overlay.marks(calibration, believed, target, CUBE)).shape == frame.shape


def test_a_block_placed_5_cm_off_is_caught_and_the_journal_records_what_was_moved(tmp_path, calibration, robot):
    # Trial 1: red_cube slips 5 cm; the operator accepts it as placed. Trial 2: it slips again; the operator fixes it.
    robot.script = ["slip", "slip", "exact"]
    answers = ["", "a", "", "", "", ""]
    view = rr.RecordingStream("lerobot_contrast_staging")
    logged = view.memory_recording()
    run(evaluation(tmp_path / "run", calibration, robot, answers, "--cost=measured", recording=view))
    first, second = journal(tmp_path / "run")[:2]
    staged = first["extra"]["staging"]
    assert staged["accepted_off"] == ["red_cube"] and staged["off_m"]["red_cube"] == pytest.approx(OFF, abs=0.01)
    target = first["instance"]["scene"]["objects"]["red_cube"]
    assert staged["placed"]["red_cube"] == pytest.approx([target[0], target[1] + OFF], abs=0.01)
    # What was moved: from where the blocks were to where they were put, slip included, not the planned distance.
    before = Scene({name: Pose(*pose) for name, pose in staged["before"].items()})
    slipped = Scene.from_json(first["instance"]["scene"]).with_object("red_cube", Pose(target[0], target[1] + OFF))
    assert staged["moved_m"] == pytest.approx(
        load_task_file("so101_blocks").cost_model("distance")(before, slipped), abs=0.02
    )
    assert abs(staged["moved_m"] - staged["planned_cost"]) > 0.03
    assert first["cost"] == pytest.approx(staged["moved_m"], abs=1e-4)  # --cost=measured
    assert second["extra"]["staging"]["accepted_off"] == []  # fixed, then measured again within 2 cm
    assert second["cost"] == pytest.approx(second["extra"]["staging"]["moved_m"], abs=1e-4)
    # The live view showed the camera with the targets, the arrows and the console's text.
    (tmp_path / "view.rrd").write_bytes(logged.drain_as_bytes())
    entities = {chunk.entity_path for chunk in RrdReader(str(tmp_path / "view.rrd")).stream().to_chunks()}
    assert {f"/staging/{path}" for path in ("camera", "camera/targets", "camera/arrows", "console")} <= entities


def test_resume_after_a_stop_mid_staging_keeps_the_measured_scene(tmp_path, calibration, robot):
    run_dir = tmp_path / "run"
    robot.script = ["slip"]
    with pytest.raises(SessionStopped):  # the input ends at the fix-or-accept question
        run(evaluation(run_dir, calibration, robot, [""]))
    assert json.loads((run_dir / MEMORY).read_text())["trial"] == 0
    # On resume the blocks are where the operator left them; they accept the slip as placed.
    robot.script = ["none"]
    run(dataclasses.replace(evaluation(run_dir, calibration, robot, ["", "a", "", "", ""]), resume=True))
    first = journal(run_dir)[0]["extra"]["staging"]
    assert first["accepted_off"] == ["red_cube"]
    # The effort before the stop counts: moved from where the blocks were before the first staging began.
    assert first["before"]["red_cube"][:2] == pytest.approx([0.15, 0.35])
    assert first["moved_m"] == pytest.approx(first["planned_cost"], abs=0.08)


class CameraOnly:
    """The simulated table seen only through its camera, as a real arm's is: it cannot report or stage its scene."""

    name = "camera_only_table"

    def __init__(self) -> None:
        self.sim = LanguageTableSim(LanguageTableSimConfig(camera=True))
        self.observation_features, self.action_features = self.sim.observation_features, self.sim.action_features
        self.connect, self.disconnect = self.sim.connect, self.sim.disconnect
        self.get_observation, self.send_action = self.sim.get_observation, self.sim.send_action

    @property
    def is_connected(self) -> bool:
        return self.sim.is_connected


def test_without_scene_reports_the_next_trial_starts_from_where_the_camera_saw_the_blocks(tmp_path, calibration):
    robot = CameraOnly()
    robot.connect()

    class SlippingHands(OperatorConsole):  # the operator stages while the console waits, red_cube 5 cm off
        def stage(self, context):
            staging = super().stage(context)
            red = context.instance.scene.objects["red_cube"]
            robot.sim.stage_scene(context.instance.scene.with_object("red_cube", Pose(red.x, red.y + OFF, red.yaw)))
            return staging

    answers = ["", "a", "n", "", "a", "n"]
    run(evaluation(tmp_path / "run", calibration, robot, answers, console_class=SlippingHands))
    first, second = journal(tmp_path / "run")[:2]
    target = first["instance"]["scene"]["objects"]["red_cube"]
    # Not the plan's target: where the camera saw the red cube after the episode, 5 cm off.
    assert first["scene_after"]["objects"]["red_cube"][:2] == pytest.approx([target[0], target[1] + OFF], abs=0.015)
    assert second["extra"]["staging"]["before"]["red_cube"][:2] == pytest.approx(
        first["scene_after"]["objects"]["red_cube"][:2], abs=0.01
    )
    robot.disconnect()


def test_the_persons_page_shows_the_cameras_overlay_of_each_trial(tmp_path, calibration, robot):
    robot.script = ["exact", "exact"]
    ev = evaluation(tmp_path / "run", calibration, robot, ["", "", "", ""])
    bench = ev.operator.bench
    bench.wants_picture = True
    page = PersonPage(0, False, Answers(io.StringIO("")), lambda: tmp_path, lambda: bench.picture)
    ev.operator.channels.append(page)
    try:
        run(ev)
        state = json.loads(urllib.request.urlopen(f"http://127.0.0.1:{page.port}/state", timeout=10).read())
        assert state["picture"] == bench.picture[0] >= 2  # before staging, and as measured after
        jpeg = urllib.request.urlopen(f"http://127.0.0.1:{page.port}/picture.jpg", timeout=10).read()
        shown = cv2.imdecode(np.frombuffer(jpeg, np.uint8), cv2.IMREAD_COLOR)
        assert shown.shape[:2] == robot.get_observation()["top"].shape[:2]  # the camera's frame, drawn on
    finally:
        page.close()
