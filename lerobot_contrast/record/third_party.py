"""Third-party output during a run: each library warning once, in one line, on the console; its full text (and the
AV1 encoder's banners) in log files in the run directory, so the run's own progress and table stay readable. While
we talk to the Hub, the Hub client's own connection and retry warnings are dropped: our one-line error says it."""

from __future__ import annotations

import errno
import logging
import os
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

LOG_FILE = "third_party.log"
# SVT-AV1 (LeRobot's video encoder) prints a 20-line banner per episode to stderr unless SVT_LOG_FILE names a file.
ENCODER_LOG_FILE = "av1_encoder.log"
OWN_LOGGERS = ("lerobot_contrast", "lerobot_robot_locobot")
USER_ENCODER_LOG = os.environ.get("SVT_LOG_FILE")
NO_SPACE = os.strerror(errno.ENOSPC)


class OnceHandler(logging.Handler):
    """Every third-party warning in full to `path`; its first line once to the console, pointing there."""

    def __init__(self, path: Path) -> None:
        super().__init__(logging.WARNING)
        self.path = path
        self.seen: set[str] = set()
        self.setFormatter(logging.Formatter("%(asctime)s %(levelname)s %(name)s: %(message)s"))

    def emit(self, record: logging.LogRecord) -> None:
        try:
            if NO_SPACE in record.getMessage():  # a full disk: the run stops and says so in its own one line
                return
            try:
                with self.path.open("a", encoding="utf-8") as log:
                    log.write(self.format(record) + "\n")
            except OSError:  # the log cannot take it (a full disk): the console line below still shows it
                pass
            lines = [line.strip() for line in record.getMessage().splitlines() if line.strip()]
            first = lines[0] if lines else record.name
            if first not in self.seen:
                self.seen.add(first)
                print(f"warning ({record.name}): {first[:160]} [full text: {self.path}]", file=sys.stderr)
        except Exception:  # a log that cannot be written must not stop the run
            self.handleError(record)


def _own(record: logging.LogRecord) -> bool:
    return record.name.startswith(OWN_LOGGERS)


@contextmanager
def third_party_output(run_dir: Path) -> Iterator[None]:
    """While a run writes into `run_dir`: library log records and `warnings` go through `OnceHandler` only;
    the project's own records reach the console's handlers as before."""
    root = logging.getLogger()
    handler = OnceHandler(run_dir / LOG_FILE)
    handler.addFilter(lambda record: not _own(record))
    saved = list(root.handlers)
    for existing in saved:
        existing.addFilter(_own)
    root.addHandler(handler)
    logging.captureWarnings(True)
    if USER_ENCODER_LOG is None:  # read when an encoder starts; a file the user named is kept
        os.environ["SVT_LOG_FILE"] = str(run_dir / ENCODER_LOG_FILE)
    try:
        yield
    finally:
        logging.captureWarnings(False)
        root.removeHandler(handler)
        for existing in saved:
            existing.removeFilter(_own)


@contextmanager
def quiet_hub_client(*also: str) -> Iterator[None]:
    """Drop huggingface_hub's log records (a warning per failed request and per retry), and those of the loggers
    named in `also`, while the block runs: when the Hub cannot be reached or has no such repo, the caller's one-line
    error is the only line the user sees."""
    loggers = [logging.getLogger(name) for name in ("huggingface_hub", *also)]
    levels = [logger.level for logger in loggers]
    for logger in loggers:  # their modules log through child loggers, which inherit the level
        logger.setLevel(logging.CRITICAL + 1)
    try:
        yield
    finally:
        for logger, level in zip(loggers, levels, strict=True):
            logger.setLevel(level)
