"""``--config FILE``: a subcommand's flags read from a TOML file (or YAML, with PyYAML),
as defaults under the command line.

Keys are the flags' names without the dashes (``prior-strength`` or ``prior_strength``);
values are what the flag takes on the command line (a string or a number; true or false
for a switch; a list for a repeatable flag), checked by the flag's own type and choices.
A flag given on the command line wins, with a note on stderr. A bad file, an unknown key
or a bad value is a usage error: one line, exit status 2, before anything runs.
"""

from __future__ import annotations

import argparse
import difflib
import sys
import tomllib
from collections.abc import Sequence
from pathlib import Path
from typing import Any


class _Unset(list):
    """A flag's placeholder while finding what the command line gave (a list: ``append``
    actions copy and extend it)."""


def _subcommand(parser: argparse.ArgumentParser, argv: Sequence[str]
                ) -> tuple[argparse.ArgumentParser, list[str]] | None:
    """The subcommand's parser and the arguments after its name, if argv names one."""
    subs = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    for i, token in enumerate(argv):
        if not token.startswith("-"):  # before the subcommand: only options
            choices: dict[str, argparse.ArgumentParser] = subs[0].choices if subs else {}
            return (choices[token], list(argv[i + 1:])) if token in choices else None
    return None


def _read(sub: argparse.ArgumentParser, path: str) -> dict[str, Any]:
    """The file's table of flags (a usage error if it cannot be read)."""
    where = f"--config {path}"
    try:
        raw = Path(path).read_bytes()
    except OSError as err:
        sub.error(f"{where}: {err.strerror or err}")
    try:
        if Path(path).suffix.lower() in (".yaml", ".yml"):
            try:
                import yaml
            except ImportError:
                sub.error(f"{where}: reading YAML needs PyYAML: pip install pyyaml, or write "
                          f"the file as TOML")
            doc = yaml.safe_load(raw) or {}
        else:
            doc = tomllib.loads(raw.decode("utf-8"))
    except Exception as err:  # TOML, YAML or UTF-8 decoding errors
        sub.error(f"{where}: not a valid {Path(path).suffix or 'TOML'} file: "
                  f"{' '.join(str(err).split())}")
    if not isinstance(doc, dict):
        sub.error(f"{where}: expected a table of flag = value, got {type(doc).__name__}")
    return doc


def _flags(sub: argparse.ArgumentParser) -> dict[str, argparse.Action]:
    """The subcommand's flags a file may set, by name without dashes."""
    return {o[2:]: a for a in sub._actions for o in a.option_strings
            if o.startswith("--") and a.dest not in ("help", "config")
            and not (isinstance(a, argparse.BooleanOptionalAction) and o.startswith("--no-"))}


def _one(action: argparse.Action, value: Any) -> Any:
    """One value as the command line's text through the flag's type and choices."""
    if isinstance(value, bool) or not isinstance(value, (str, int, float)):
        raise ValueError(f"expected a string or a number, got {value!r}")
    text = value if isinstance(value, str) else str(value)
    convert = action.type
    try:
        converted = convert(text) if callable(convert) else text
    except argparse.ArgumentTypeError as err:
        raise ValueError(str(err)) from None
    except (TypeError, ValueError):
        name = getattr(convert, "__name__", "a value")
        raise ValueError(f"expected {name}, got {value!r}") from None
    if action.choices is not None and converted not in action.choices:
        raise ValueError(f"expected one of {', '.join(map(str, action.choices))}, "
                         f"got {value!r}")
    return converted


def _value(action: argparse.Action, value: Any) -> Any:
    if action.nargs == 0:  # a switch: --physical
        if not isinstance(value, bool):
            raise ValueError(f"expected true or false, got {value!r}")
        return value
    if isinstance(action, argparse._AppendAction) or action.nargs not in (None, "?"):
        items = value if isinstance(value, list) else [value]
        return [_one(action, v) for v in items]
    return _one(action, value)


def _defaults(sub: argparse.ArgumentParser, path: str) -> dict[str, Any]:
    """The file's values by destination, checked; usage errors name key, expected, got."""
    flags, values = _flags(sub), {}
    for key, value in _read(sub, path).items():
        name = str(key).replace("_", "-")
        if name not in flags:
            close = difflib.get_close_matches(name, list(flags), n=1)
            hint = f"; did you mean {close[0]!r}?" if close else "; the keys are the flags' names"
            sub.error(f"--config {path}: unknown key {key!r}{hint}")
        action = flags[name]
        try:
            values[action.dest] = _value(action, value)
        except ValueError as err:
            sub.error(f"--config {path}: key {key!r} (--{name}): {err}")
    return values


def parse_args(parser: argparse.ArgumentParser, argv: Sequence[str]) -> argparse.Namespace:
    """``parser.parse_args(argv)`` with the subcommand's ``--config FILE`` applied as its
    defaults, and a note on stderr for each flag that the command line overrides."""
    found = _subcommand(parser, argv)
    path = None
    if found is not None and any("--config" in a.option_strings for a in found[0]._actions):
        pre = argparse.ArgumentParser(add_help=False, allow_abbrev=False)
        pre.add_argument("--config")
        path = pre.parse_known_args(found[1])[0].config
    if found is None or path is None:
        return parser.parse_args(argv)
    sub, tokens = found
    values = _defaults(sub, path)
    for action in sub._actions:  # a required flag the file gives is no longer required
        if action.dest in values:
            action.required = False
    sub.set_defaults(**values)
    args = parser.parse_args(argv)
    # what the command line gave: the flags whose placeholder was replaced
    unset = {dest: _Unset() for dest in values}
    given = sub.parse_known_args(tokens, argparse.Namespace(**unset))[0]
    for action in sub._actions:
        if action.dest in unset and getattr(given, action.dest) is not unset[action.dest]:
            flag = next(o for o in action.option_strings if o.startswith("--"))
            print(f"sedsabso-jax: note: {flag} from the command line overrides {path}'s value",
                  file=sys.stderr)
            if isinstance(action, argparse._AppendAction):  # not added to the file's items
                setattr(args, action.dest, list(getattr(given, action.dest)))
            unset.pop(action.dest)
    return args
