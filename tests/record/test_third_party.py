"""A recorded run's console shows its progress and table: library warnings once, in one line, full text in a file."""

import logging
import subprocess
import sys
import warnings

from lerobot_contrast.record.dataset import video_backend
from lerobot_contrast.record.third_party import LOG_FILE, third_party_output


def test_a_recorded_three_instance_run_prints_its_trials_and_table_and_little_else(tmp_path):
    run = tmp_path / "run"
    command = [sys.executable, "-m", "lerobot_contrast.eval", "--n_instances=3", "--record_dataset=true"]
    command += ["--rerun=false", "--policy.type=oracle", "--perturbations=[LB1,SB2]", f"--output_dir={run}"]
    done = subprocess.run(command, capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert done.returncode == 0, done.stderr[-2000:]
    lines = (done.stdout + done.stderr).splitlines()
    # Ours: the header, the progress lines, the table and how to read it, the run directory, library warnings in one
    # line each; nothing else.
    ours = ("task ", "plan: ", "run directory: ", "stop any time", "trial ", "9/9 trials", "perturbation ", "---")
    ours += ("original ", "ΔLB1 ", "ΔSB2 ", "all ", "How to read: ", "warning (")
    assert all(line.startswith(ours) for line in lines), "\n".join(lines)
    assert "9/9 trials · " in done.stdout and sum(line.startswith("all ") for line in lines) == 1
    assert sum(line.startswith("warning (") for line in lines) <= 2
    assert not any(word in done.stdout + done.stderr for word in ("Svt[", "Traceback", "libtorchcodec", "Map:"))
    assert (run / "dataset" / "meta" / "info.json").is_file()


def test_a_library_warning_shows_once_in_one_line_with_its_full_text_in_the_run_directory(tmp_path, capsys):
    library = logging.getLogger("somelib.loader")
    with third_party_output(tmp_path):
        for _ in range(3):
            library.warning("Could not load libfoo. Likely causes:\n  1. a long\n  2. traceback")
        warnings.warn("deprecated thing", DeprecationWarning, stacklevel=1)
        logging.getLogger("lerobot_contrast.record.hub").warning("our own")
    err = capsys.readouterr().err.splitlines()
    shown = [line for line in err if line.startswith("warning (")]
    assert shown[0].startswith("warning (somelib.loader): Could not load libfoo. Likely causes: [full text: ")
    assert len(shown) == 2 and "deprecated thing" in shown[1]
    full = (tmp_path / LOG_FILE).read_text()
    assert full.count("Could not load libfoo") == 3 and full.count("2. traceback") == 3
    assert "our own" not in full


def test_pyav_decodes_where_torchcodec_cannot_load():
    try:
        import torchcodec.decoders  # noqa: F401
    except (ImportError, OSError, RuntimeError):
        assert video_backend() == "pyav"
    else:
        assert video_backend() == "torchcodec"


def test_a_full_disk_adds_no_warning_line_and_an_unwritable_log_no_traceback(tmp_path, capsys):
    library = logging.getLogger("somelib.encoder")
    with third_party_output(tmp_path / "gone"):  # the log file cannot be opened: its folder does not exist
        library.error("Encoder thread error: [Errno 28] No space left on device: 'x.mp4'")
        library.warning("something else")
    err = capsys.readouterr().err
    assert err.splitlines() == [
        f"warning (somelib.encoder): something else [full text: {tmp_path / 'gone' / LOG_FILE}]"
    ]
