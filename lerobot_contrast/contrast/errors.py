"""User-facing errors: bad input that the command line reports as one line, without a traceback."""


class UserError(ValueError):
    """Bad input: the message names the flag or file at fault and what to do about it."""
