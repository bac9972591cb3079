"""The paper's navigation study (the shipped sweep file paper_vln, run and analysed by scripts/study/reproduce_paper_vln.py): its
sweep file expands into the designs the analysis reads, its verdicts follow the numbers, and a tiny run writes the
whole report."""

import re

import pytest
import ray

from lerobot_contrast.reporting import load_run
from lerobot_contrast.reporting.stats import Estimate
from lerobot_contrast.sweep.cells import read_sweep_file, studies_dir, sweep_cells
from tests.study_scripts import load_script


def study_module():
    return load_script("reproduce_paper_vln")


def test_the_scaled_study_is_three_seeds_of_100_sampled_arrangements_and_holds_every_design_it_analyses(tmp_path):
    path = studies_dir() / "paper_vln.yaml"
    cells = sweep_cells(path, read_sweep_file(path), tmp_path)
    assert {cell.config.seed for cell in cells} == {0, 1, 2}
    assert all(cell.config.task == "vln" and cell.config.n_instances == 100 for cell in cells)
    study = study_module()
    read = {name for pair in study.ERROR_DESIGNS.values() for name in pair} - set(study.AXIS_PAIRS)
    assert {*read, "contrast_all4", "route_follower_contrast_all4"} <= {cell.label for cell in cells}
    assert not set(study.AXIS_PAIRS) & {cell.label for cell in cells}  # the axis pairs are kept from all four
    assert {cell.config.policy.type for cell in cells if cell.label.startswith("route_follower")} == {"route_follower"}


def estimate(mean: float, low: float | None = None, high: float | None = None) -> Estimate:
    return Estimate(mean, mean if low is None else low, mean if high is None else high, 15, 5, "test")


def verdict_lines(progress: dict, paired: dict, calibration: dict) -> list[str]:
    found = {"trials_all4": 40, "trials_standard": 10, "error_all4": 0.02}
    reset = {"trials_all4": 30, "trials_standard": 10, "error_all4": 0.03}
    return study_module().verdicts(progress, paired, 0.6, found, reset, calibration)


def test_each_finding_holds_when_the_numbers_agree_with_the_paper_and_not_otherwise():
    paper_like = {"original": 0.6, "L": 0.5, "S": 0.4, "LB": 0.7, "SB": 0.75}
    paired = {"L": estimate(-0.1, -0.2, -0.01), "S": estimate(-0.2, -0.3, 0.05)}
    blind = {"L": estimate(0.0), "LB": estimate(0.0)}
    lines = verdict_lines({k: estimate(v) for k, v in paper_like.items()}, paired, blind)
    assert len(lines) == 5 and all("**holds**" in line for line in lines)
    assert "resolved" in lines[1] and "within the interval of no change" in lines[1]
    assert "ΔLB 0.700 [0.700, 0.700] (+17%" in lines[2]
    reversed_ = {"original": 0.6, "L": 0.7, "S": 0.4, "LB": 0.5, "SB": 0.75}
    lines = verdict_lines({k: estimate(v) for k, v in reversed_.items()}, {}, {"L": estimate(0.1), "LB": estimate(0)})
    assert ["**does not hold**" in line for line in lines] == [False, True, True, False, True]
    tied = {k: estimate(0.6) for k in ("original", "L", "S", "LB", "SB")}
    assert all("**does not hold**" in line for line in verdict_lines(tied, {}, blind)[1:3])  # a tie is no finding
    # Above the full set on average, but the full set's 0.6 lies inside its interval: a tie as well.
    wide = {**{k: estimate(v) for k, v in paper_like.items()}, "SB": estimate(0.65, 0.55, 0.75)}
    assert "**does not hold**" in verdict_lines(wide, paired, blind)[2]
    # The route follower off its ceiling on a new goal is not calibrated, even with ΔL unchanged.
    assert "**does not hold**" in verdict_lines(wide, paired, {**blind, "SB": estimate(-0.2)})[4]


@pytest.mark.slow
def test_a_tiny_study_writes_the_tables_and_a_verdict_per_finding(tmp_path):
    study = study_module()
    args = ["--output_dir", str(tmp_path), "--n_instances", "2", "--seeds", "0", "--repeats", "1"]
    try:
        study.main([*args, "--max_episode_steps", "6", "--num_cpus", "1"])
    finally:
        ray.shutdown()  # the study joins a local Ray in this process; later tests in it start their own
    report = (tmp_path / "reproduction.md").read_text(encoding="utf-8")
    assert "x 1 repeats = 25 trials" in report and "## At scale: 1 seeds x 2 sampled arrangements" in report
    for row in ("standard evaluation's cost per instance", "trials within 35 m", "contrast, all four, reset seconds"):
        assert row in report
    assert report.count("| ΔSB |") == 4  # learned and route follower, paper design and at scale
    findings = re.findall(r"^\d\. .*\*\*(holds|does not hold)\*\*", report, flags=re.MULTILINE)
    assert len(findings) == 5
    # An axis pair is the all-four run kept to its originals and the pair's trials, charged from the scene the
    # previous kept trial left: kept to all four axes, it is the run itself, cost for cost.
    all4 = load_run(str(tmp_path / "runs" / "contrast_all4,seed=0"))
    itself = study.kept_to(all4, study.PERTURBATIONS).results.sort_values("index")
    assert itself["cumulative_cost"].tolist() == all4.results.sort_values("index")["cumulative_cost"].tolist()
    language = study.kept_to(all4, ("L", "LB")).results
    assert set(language["axis"].dropna()) <= {"L", "LB"} and len(language) == 3 * 2
    assert "| contrast, ΔL + ΔLB |" in report
