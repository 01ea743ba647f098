"""orbatt's exceptions. Each also inherits the built-in a caller would catch otherwise."""
from __future__ import annotations


class OrbattError(Exception):
    """Base class of every orbatt error."""


class InputError(OrbattError, ValueError):
    """Bad input: the message names the field, the value and the fix."""


class IntegrationError(OrbattError, RuntimeError):
    """An integration could not continue (non-finite state, step size underflow, ...);
    ``t`` is the time at which it stopped."""

    def __init__(self, message, t=None):
        super().__init__(message)
        self.t = t


class ScenarioError(InputError):
    """A scenario file is malformed; the message names the file, table, key, value and fix."""


class SweepError(OrbattError, RuntimeError):
    """A sweep could not finish (a task failed for good, e.g. its workers kept dying); the
    chunks written so far are kept for ``resume``."""


def not_a_file(path):
    """Why ``path`` cannot be read as a file, for a message (``"does not exist"``, ``"is a
    folder"``, ``"is a FIFO (named pipe)"``, ``"is a broken symbolic link"`` ...), or None for a
    regular file (or a link to one). Never opens it (a FIFO would block)."""
    import os
    import stat

    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        return "is a broken symbolic link" if os.path.islink(path) else "does not exist"
    except NotADirectoryError:
        return "does not exist (a part of its path is a file, not a folder)"
    except OSError as exc:
        return f"cannot be read ({exc.strerror or exc})"
    if stat.S_ISREG(mode):
        return None
    for test, what in ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
                       (stat.S_ISSOCK, "a socket"), (stat.S_ISCHR, "a character device"),
                       (stat.S_ISBLK, "a block device")):
        if test(mode):
            return f"is {what}, not a file"
    return "is not a regular file"
