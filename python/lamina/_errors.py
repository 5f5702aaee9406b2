"""The package's exceptions and warnings, importable (and picklable) from ``lamina``."""

from __future__ import annotations


class LaminaError(ValueError):
    """A stage refused its input or options: the message names the argument (``tolerance=``,
    ``positions[3]``) or the file and place, and what was wrong."""

    __module__ = "lamina"


class LaminaWarning(UserWarning):
    """A note of a stage: a default it took, something it read but did not use, a scale that
    looks wrong for the model."""

    __module__ = "lamina"


class Cancelled(KeyboardInterrupt):
    """The progress callback returned False: the stage stopped at its next check and left
    nothing behind. A KeyboardInterrupt, as Ctrl-C is."""

    __module__ = "lamina"
