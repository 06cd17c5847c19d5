"""The exception type for problems a user can fix (bad input, missing files)."""

__all__ = ["UserError"]


class UserError(Exception):
    """A problem with the user's input; the CLIs print its message as one line, exit 2.

    The message says what is wrong and what to do about it.
    """
