"""Checks of arguments that every layer takes alike.

One place for each check, so that every function refuses the same bad value
with the same message, naming the argument and the value received.
"""

from __future__ import annotations

from .errors import HandsynthError, InvalidInputError

__all__ = ["SIDES", "check_options", "check_side"]

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


def check_options(options, cls: type, *, name: str = "options",
                  error: type[HandsynthError] = InvalidInputError):
    """`options` checked to be an instance of the dataclass `cls`; ``cls()`` for None.

    Parameters
    ----------
    options : object
        What was given.
    cls : type
        The options class (``SearchOptions``); made with its defaults for None.
    name : str, keyword-only
        The argument's name, for the message.
    error : HandsynthError subclass, keyword-only
        Class of the error raised.

    Returns
    -------
    cls instance

    Raises
    ------
    HandsynthError
        (`error`) anything else, named with its type and value: a dict of
        fields (``{}`` is not the defaults), the fields' values alone, or
        options of another class.
    """
    if options is None:
        return cls()
    if not isinstance(options, cls):
        value = repr(options)
        value = value if len(value) <= 60 else value[:57] + "..."
        hint = f" (make one: {cls.__name__}(**fields))" if isinstance(options, dict) else ""
        article = "an" if cls.__name__[:1] in "AEIOU" else "a"
        raise error(f"{name} must be {article} {cls.__name__}, got {type(options).__name__} "
                    f"{value}{hint}")
    return options
