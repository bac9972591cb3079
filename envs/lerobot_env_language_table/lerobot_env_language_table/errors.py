"""The one error both the env config and the env raise, kept apart so neither imports the other for it."""


class EnvFlagError(SystemExit):
    """A bad `--env.*` value. LeRobot's commands print a SystemExit's message as one line, without a traceback."""
