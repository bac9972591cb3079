"""`python -m lerobot_contrast.report` on small simulator runs: report.md, figures, comparisons and bad input."""

import shutil
import subprocess
import sys

import pytest
from matplotlib.image import imread

from lerobot_contrast.eval import main as eval_main
from lerobot_contrast.report import main
from lerobot_contrast.reporting import load_run

PLAN = ["--n_instances=4", "--max_episode_steps=80", "--policy.type=oracle", "--policy.noise_std=0.01"]
RUNS = {
    "standard-0": ["--strategy=standard", "--seed=0"],
    "standard-1": ["--strategy=standard", "--seed=1"],
    "contrast-0": ["--strategy=contrast", "--perturbations=[LB1,LB2,SB1,SB2]", "--seed=0"],
    "contrast-1": ["--strategy=contrast", "--perturbations=[LB1,LB2,SB1,SB2]", "--seed=1"],
    "blind-0": [
        "--strategy=contrast",
        "--perturbations=[LB1,LB2,SB1,SB2]",
        "--seed=0",
        "--policy.language_blind=1.0",
    ],
}


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    root = tmp_path_factory.mktemp("runs")
    for name, flags in RUNS.items():
        assert eval_main([*PLAN, *flags, f"--output_dir={root / name}"]) == 0
    return root


def test_a_report_over_several_runs_writes_tables_settings_and_readable_figures(runs, tmp_path, capsys):
    out = tmp_path / "report"
    assert main([str(runs / name) for name in RUNS] + [f"--output_dir={out}"]) == 0
    assert capsys.readouterr().out.strip() == f"report: {out / 'report.md'}"
    text = (out / "report.md").read_text()
    # Seeds of one design are pooled; the two policies get their own rows and a paired comparison.
    assert "| oracle (noise std 0.01): contrast ΔLB1+ΔLB2+ΔSB1+ΔSB2 (pooled) | 0,1 |" in text
    assert "oracle (noise std 0.01, language blind 1): contrast ΔLB1+ΔLB2+ΔSB1+ΔSB2" in text
    assert "## Policies on the same plan" in text and "| contrast-0 | blind-0 |" in text
    assert "## Sensitivity" in text and "| ΔLB2 |" in text
    assert "## Against the full i.i.d. evaluation" in text and "No estimation-error panel" not in text
    assert all(f"**{name}**" in text for name in RUNS) and "`policy.language_blind=1.0`" in text
    for figure in ("perturbations_spl.png", "error_vs_cost_spl.png", "trials_vs_cost.png"):
        assert f"]({figure})" in text
        height, width, _ = imread(out / figure).shape
        assert width > 600 and height > 400


def test_without_a_standard_run_the_report_says_why_the_error_panel_is_missing(runs):
    assert main([str(runs / "contrast-0")]) == 0
    report = runs / "contrast-0" / "report"
    text = (report / "report.md").read_text()
    assert "No estimation-error panel: no standard run among the inputs" in text
    assert not (report / "error_vs_cost_spl.png").exists() and (report / "trials_vs_cost.png").exists()


def test_a_run_still_being_written_is_read_from_its_journal_without_touching_it(runs, tmp_path):
    live = tmp_path / "live"
    shutil.copytree(runs / "contrast-1", live)
    (live / "results.parquet").unlink()
    (live / "summary.json").unlink()
    journal = live / "journal.jsonl"
    lines = journal.read_bytes().splitlines(keepends=True)
    torn = b"".join(lines[:3]) + lines[3][:40]  # the writer is mid-line
    journal.write_bytes(torn)
    run = load_run(str(live))
    assert len(run.results) == 3 and not run.complete
    assert journal.read_bytes() == torn
    assert main([str(live)]) == 0
    assert "live is incomplete" in (live / "report" / "report.md").read_text()


@pytest.mark.parametrize(
    ("args", "message"),
    [
        ([], "error: give the run directories to report on: python -m lerobot_contrast.report RUN_DIR"),
        (["{missing}"], "error: {missing}: no such run directory; pass directories written by lerobot_contrast.eval"),
        (
            ["{empty}"],
            "error: {empty}: not a run directory (no config.json); pass the folder lerobot_contrast.eval wrote",
        ),
        (["{run}", "--metric=speed"], "error: --metric must be one of success, spl, progress, got 'speed'"),
        (["{run}", "--output_dir={blocked}/report"], "error: --output_dir: cannot write to {blocked}/report"),
    ],
)
def test_bad_input_gets_one_line_naming_what_is_wrong(runs, tmp_path, capsys, args, message):
    paths = {"missing": tmp_path / "nope", "empty": tmp_path, "run": runs / "standard-0", "blocked": tmp_path / "file"}
    (tmp_path / "file").write_text("not a directory")
    assert main([a.format(**paths) for a in args]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and err.startswith(message.format(**paths))


def test_the_module_runs_as_a_command(tmp_path):
    result = subprocess.run(
        [sys.executable, "-m", "lerobot_contrast.report", str(tmp_path / "nope")], capture_output=True, text=True
    )
    assert (
        result.returncode == 2
        and result.stderr
        == f"error: {tmp_path / 'nope'}: no such run directory; pass directories written by lerobot_contrast.eval\n"
    )


def test_a_value_that_rounds_to_zero_has_no_sign_in_report_md():
    from lerobot_contrast.reporting.markdown import fmt, num
    from lerobot_contrast.reporting.stats import Estimate

    assert fmt(Estimate(-0.0, -0.0001, 0.0, 3, 3, "cluster_bootstrap")) == "0.000 [0.000, 0.000]"
    assert fmt(Estimate(-0.25, -0.5, -0.0004, 3, 3, "cluster_bootstrap")) == "-0.250 [-0.500, 0.000]"
    assert num(-0.0002, "+.3f") == "+0.000"


def test_the_sensitivity_figure_gives_each_bar_its_n_and_marks_no_trials_n_a():
    from lerobot_contrast.reporting.figures import perturbation_plot
    from lerobot_contrast.reporting.stats import Estimate

    nan = float("nan")
    table = {
        "contrast": {
            "original": Estimate(0.5, 0.2, 0.8, 4, 4, "cluster_bootstrap"),
            "LB1": Estimate(0.0, 0.0, 0.0, 1, 1, "cluster_bootstrap"),  # scored 0: a bar of 0 with its n
            "SB1": Estimate(nan, nan, nan, 0, 0, "none"),  # no trials
        }
    }
    fig = perturbation_plot(table, ["original", "LB1", "SB1", "SB2"], "spl", None, {"contrast": "C0"})
    texts = {(round(t.get_position()[0]), t.get_text()) for t in fig.axes[0].texts}
    assert texts == {(0, "n=4"), (1, "n=1"), (2, "n/a")}
    bars = [patch.get_x() + patch.get_width() / 2 for patch in fig.axes[0].patches]
    assert [round(x) for x in bars] == [0, 1]


def test_the_same_run_given_twice_is_counted_once_and_named_in_one_line(tmp_path, capsys):
    run = tmp_path / "run"
    flags = ["--n_instances=2", "--policy.type=oracle", "--perturbations=[LB1]", "--rerun=false"]
    assert eval_main([*flags, "--max_episode_steps=20", f"--output_dir={run}"]) == 0
    copy = tmp_path / "downloaded"  # as a hub: copy lands elsewhere, holding the same files
    shutil.copytree(run, copy)
    (copy / "journal.jsonl").unlink()  # read from results.parquet instead, as a publication may be
    capsys.readouterr()
    assert main([str(run), str(copy), str(run), f"--output_dir={tmp_path / 'report'}"]) == 0
    out = capsys.readouterr().out.splitlines()
    notes = [line for line in out if line.startswith("note: ")]
    assert notes == [
        f"note: {copy} is the same run as {run}; it is counted once",
        f"note: {run} is the same run as {run}; it is counted once",
    ]
    text = (tmp_path / "report" / "report.md").read_text()
    rows = [line for line in text.splitlines() if line.startswith("| contrast")]
    assert len(rows) == 1 and "| 0 |" in rows[0]  # seed 0, once, and no pooled row of two "seeds"
    other = tmp_path / "other"
    assert eval_main([*flags, "--max_episode_steps=20", "--seed=1", f"--output_dir={other}"]) == 0
    assert load_run(str(other)).identity != load_run(str(run)).identity


def test_a_run_of_the_default_policy_is_labelled_with_its_name_not_as_the_oracle():
    from lerobot_contrast.policies import DEFAULT_POLICY
    from lerobot_contrast.reporting.runs import policy_label

    assert policy_label({"policy": {"type": None, "path": None}}) == DEFAULT_POLICY
    assert policy_label({"policy": {"type": "oracle", "noise_std": 0.01}}) == "oracle (noise std 0.01)"


def test_each_policy_gets_its_own_full_iid_line_and_the_settings_show_the_values_used(runs, tmp_path):
    from lerobot_contrast.reporting.build import full_values
    from lerobot_contrast.reporting.figures import perturbation_plot
    from lerobot_contrast.reporting.markdown import used_settings

    blind = tmp_path / "standard-blind-0"
    assert eval_main([*PLAN, *RUNS["standard-0"], "--policy.language_blind=1.0", f"--output_dir={blind}"]) == 0
    loaded = [load_run(str(path)) for path in (runs / "standard-0", runs / "contrast-0", blind, runs / "blind-0")]
    full = full_values(loaded, "spl")
    assert list(full) == ["oracle (noise std 0.01)", "oracle (noise std 0.01, language blind 1)"]
    fig = perturbation_plot({}, ["original"], "spl", full, {})
    labels = [line.get_label() for line in fig.axes[0].lines]  # the lines across the panel
    assert [label.rsplit(" (", 1)[0] for label in labels] == [f"full i.i.d. evaluation, {policy}" for policy in full]
    used = used_settings({"task": "language_table", "strategy": "contrast", "n_instances": None, "perturbations": None})
    assert used["n_instances"] == 50 and used["perturbations"] == "L,LB1,LB2,S,SB1,SB2"
