"""The paper's study (the shipped sweep file paper_sim, analysed by scripts/study/reproduce_paper_sim.py) stays runnable:
its sweep file expands into valid simulated cells of the learned default, and every design the analysis reads is in it."""

from lerobot_contrast.sweep.cells import read_sweep_file, studies_dir, sweep_cells
from tests.study_scripts import load_script


def analysis_module():
    return load_script("reproduce_paper_sim")


def test_the_study_is_five_designs_and_an_oracle_calibration_over_three_seeds_of_the_learned_default(tmp_path):
    path = studies_dir() / "paper_sim.yaml"
    cells = sweep_cells(path, read_sweep_file(path), tmp_path)
    assert len(cells) == 7 * 3 and len({cell.name for cell in cells}) == len(cells)
    assert {cell.config.seed for cell in cells} == {0, 1, 2}
    assert all(cell.config.task == "language_table" and cell.config.n_instances == 250 for cell in cells)
    learned = [cell for cell in cells if not cell.label.startswith("oracle_")]
    assert all(cell.config.policy.type is None and cell.config.policy.path is None for cell in learned)
    assert all(cell.config.policy.type == "oracle" for cell in cells if cell.label.startswith("oracle_"))
    assert {cell.shared for cell in cells} == {tmp_path.resolve() / "shared_episodes"}  # repeated originals run once


def test_every_design_the_analysis_reads_is_a_cell_of_the_study(tmp_path):
    path = studies_dir() / "paper_sim.yaml"
    labels = {cell.label for cell in sweep_cells(path, read_sweep_file(path), tmp_path)}
    study = analysis_module()
    assert {*study.PAPER, *study.CALIBRATION, "standard", "oracle_standard"} <= labels
