"""The report's section on the camera's labels: with an audit, prediction-powered estimates beside the camera's,
the camera against the person, and its error; without one, that the rates take the camera as right."""

from pathlib import Path
from types import SimpleNamespace

import numpy as np

from lerobot_contrast.contrast.trial import TrialRecord
from lerobot_contrast.reporting.audit import audit_section
from lerobot_contrast.reporting.stats import frame


def records(audit_share: float) -> list[TrialRecord]:
    """40 bases, each an original and an S1 trial; the camera calls 1 in 10 failures a success."""
    rng = np.random.default_rng(3)
    out = []
    for base in range(40):
        for k, perturbation in enumerate((None, "S1")):
            truth = bool(rng.random() < (0.7 if perturbation is None else 0.4))
            said = truth or bool(rng.random() < 0.1)
            extra = {"audit": truth} if rng.random() < audit_share else {}
            index = 2 * base + k
            out.append(TrialRecord(index, f"b{base}", perturbation, None if perturbation is None else "S", "f",
                                   "in_place", 0, "done", None, 0.0, 0.0, success=said, extra=extra))  # fmt: skip
    return out


def run(name: str, audit_share: float, operator: str = "arm", path=None):
    return SimpleNamespace(name=name, results=frame(records(audit_share)), config={"operator": operator}, summary={},
                           path=path)  # fmt: skip


def test_an_audited_run_gets_estimates_a_confusion_table_and_the_cameras_error():
    lines = audit_section([run("audited", 0.3, path=Path("/nonexistent"))])
    assert lines[0] == "## Labels the camera gave"
    row = next(line for line in lines if line.startswith("| audited |"))
    cells = [cell.strip() for cell in row.strip("|").split("|")]
    assert cells[1].endswith("of 80") and cells[2].count("[") == 1 and cells[3].count("[") == 1
    assert cells[5].startswith("S/S ") and "F/S 0" in cells[5]  # the camera never calls a success a failure here
    change = next(line for line in lines if line.startswith("| audited | ΔS1"))
    assert "| 40 |" in change


def test_without_an_audit_the_report_says_the_rates_take_the_camera_as_right():
    lines = audit_section([run("plain", 0.0, path=Path("/nonexistent"))])
    assert any("no trial was audited" in line and "take every label the camera gave as right" in line for line in lines)
    assert audit_section([run("console", 0.3, operator="console")]) == []


def test_a_trial_journalled_with_the_cameras_label_before_a_kill_is_audited_later_from_audit_jsonl(tmp_path):
    """--arm.audit_at=viewer: the camera's label is journalled at once and marked drawn; a session killed before
    anyone labels it loses nothing, the report says what still waits, and a label given later in the viewer counts."""
    from lerobot_contrast.record.audit_labels import append_label

    drawn = [r for r in records(0.0) if r.index % 5 == 0]
    for record in drawn:
        record.extra["audit_drawn"] = True
    later = run("later", 0.0, path=tmp_path)
    later.results = frame([*(r for r in records(0.0) if r.index % 5), *drawn])
    waiting = audit_section([later])
    assert any(f"{len(drawn)} trial(s) drawn for the audit still wait" in line for line in waiting)
    assert any("no trial was audited" in line for line in waiting)
    for record in drawn:
        append_label(tmp_path, record.index, bool(record.success), 3.0)
    lines = audit_section([later])
    row = next(line for line in lines if line.startswith("| later |"))
    assert f"{len(drawn)} of 80" in row and not any("still wait" in line for line in lines)
    assert any(f"took 3.0 s per audited trial on the viewer's audit page after its episode ended (median of "
               f"{len(drawn)}" in line for line in lines)  # fmt: skip
