"""Keyword options as the command line's flags: the native functions that run a CLI command
(``render``, ``convert``) parse them with the CLI's own clap definitions, so that an option
means exactly what its flag means."""

from __future__ import annotations

import numbers
import os
from typing import Any, List, Mapping

__all__ = ["argv_of"]


def argv_of(options: Mapping[str, Any]) -> List[str]:
    """The flags ``options`` stand for, in their order.

    ``name=value`` is ``--name=value`` (underscores in the name become hyphens: ``max_nodes=8``
    is ``--max-nodes=8``; one argument, so a value starting with "-" is not taken for a flag),
    ``True`` is ``--name``, ``False`` and ``None`` leave the flag out, and a list or tuple is its
    items joined by commas (``orbit=(120, 15)`` is ``--orbit=120,15``). Numbers are written
    exactly (``repr`` of a float), paths as paths.
    """
    argv = []
    for name, value in options.items():
        flag = "--" + name.replace("_", "-")
        if value is None or (_is_bool(value) and not value):
            continue
        if _is_bool(value):
            argv.append(flag)
        elif isinstance(value, (list, tuple)):
            argv.append(flag + "=" + ",".join(_text(v, name) for v in value))
        else:
            argv.append(flag + "=" + _text(value, name))
    return argv


def _is_bool(value: Any) -> bool:
    # numpy's bool_ is not a bool (nor a number): recognised by its type's name.
    return isinstance(value, bool) or type(value).__name__ == "bool_"


def _text(value: Any, name: str) -> str:
    """One value as the flag takes it."""
    if _is_bool(value):
        raise ValueError(f"{name}: {value!r} inside a list; give True or False alone")
    if isinstance(value, numbers.Integral):
        return str(int(value))
    if isinstance(value, numbers.Real):
        return repr(float(value))
    if isinstance(value, (str, os.PathLike)):
        return os.fspath(value)
    raise ValueError(
        f"{name}={value!r}: give a string, a number, a path, True/False, or a list of these"
    )
