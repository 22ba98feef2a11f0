"""Checks of arguments that every layer takes alike.

One place for each check, so that every function refuses the same bad value
with the same message, naming the argument and the value received.
"""

from __future__ import annotations

from .errors import HandsynthError, InvalidInputError

__all__ = ["SIDES", "check_side"]

#: The hands a device or a model can be on.
SIDES = ("right", "left")


def check_side(side, *, name: str = "side", error: type[HandsynthError] = InvalidInputError) -> str:
    """`side`, refused unless it is ``"right"`` or ``"left"`` (case matters).

    Parameters
    ----------
    side : object
        What was given.
    name : str, keyword-only
        The argument's name, for the message (``"EvalOptions.side"``).
    error : HandsynthError subclass, keyword-only
        Class of the error raised.

    Returns
    -------
    str

    Raises
    ------
    HandsynthError
        (`error`) anything else, named with the value received (``'Right'``
        is refused: a misspelt side would otherwise read as the other hand).
    """
    if side not in SIDES:
        raise error(f"{name} must be 'right' or 'left', got {side!r}")
    return side
