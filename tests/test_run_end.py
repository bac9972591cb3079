"""A run that ends before its plan: Ctrl-C, the operator's stop and a lost robot each say one line on how to continue,
with one exit code each, for a single run and for an interleaved session alike."""

import pytest

from lerobot_contrast.operators.base import SessionStopped
from lerobot_contrast.spine.run_end import ENDED_EARLY, say_ended_early
from lerobot_contrast.spine.runner import RobotLostError

RESUME = "--output_dir=out --resume=true"


@pytest.mark.parametrize(
    ("error", "code", "stream", "line"),
    [
        (KeyboardInterrupt(), 130, "err", "\ninterrupted: every finished trial is in out/journal.jsonl; "),
        (SessionStopped("the operator pressed q"), 0, "out", "stopped: the operator pressed q; 7 trials recorded; "),
        (RobotLostError("the robot (toy) disconnected and could not reconnect"), 2, "err", "error: the robot (toy) "),
    ],
)
def test_each_early_end_is_one_line_with_its_exit_code_and_how_to_continue(capsys, error, code, stream, line):
    assert isinstance(error, ENDED_EARLY)
    assert say_ended_early(error, RESUME, "in out/journal.jsonl", recorded=lambda: 7) == code
    said = capsys.readouterr()
    text, other = (said.err, said.out) if stream == "err" else (said.out, said.err)
    assert text.startswith(line) and text.endswith(f" {RESUME}\n") and text.strip().count("\n") == 0
    assert other == ""


def test_without_a_count_the_stop_names_no_number(capsys):
    """An interleaved session has a journal per policy: its stop line counts none of them."""
    assert say_ended_early(SessionStopped("input ended"), RESUME, "journalled") == 0
    assert capsys.readouterr().out == f"stopped: input ended; continue with {RESUME}\n"


def test_the_interrupted_line_says_where_the_trials_are_kept(capsys):
    assert say_ended_early(KeyboardInterrupt(), RESUME, "journalled") == 130
    assert capsys.readouterr().err == f"\ninterrupted: every finished trial is journalled; continue with {RESUME}\n"
