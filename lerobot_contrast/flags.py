"""Command-line flags over a draccus config: `--name=value` or `--name value`, one-line errors that suggest the flag
meant, and a --help that lists the command's own flags first and a robot's fields only for the chosen --robot.type."""

from __future__ import annotations

import dataclasses
import difflib
import re
import sys
import textwrap
import typing
from pathlib import Path
from typing import Any

import draccus
from draccus.wrappers.docstring import get_attribute_docstring

from lerobot_contrast.config import ConfigError

HELP = ("--help", "-h")
WIDTH = 100


def flag_types(cls: type, prefix: str = "") -> dict[str, Any]:
    """Every flag of `cls` (nested dataclasses as dotted names) with its type."""
    types: dict[str, Any] = {}
    hints = typing.get_type_hints(cls)
    for f in dataclasses.fields(cls):
        name = prefix + f.name
        types[name] = hints[f.name]
        default = _default(f)
        if dataclasses.is_dataclass(default):
            types |= flag_types(type(default), name + ".")
    return types


def _default(f: dataclasses.Field) -> Any:
    return f.default_factory() if f.default_factory is not dataclasses.MISSING else f.default


def join_values(argv: list[str]) -> list[str]:
    """`--name value` as `--name=value`, the form LeRobot's own commands also accept."""
    out: list[str] = []
    args = iter(argv)
    for arg in args:
        if arg.startswith("--") and "=" not in arg and arg not in HELP:
            value = next(args, None)
            if value is not None and not value.startswith("--"):
                out.append(f"{arg}={value}")
                continue
            out.append(arg)
            if value is not None:
                out.append(value)
            continue
        out.append(arg)
    return out


def _is_list(tp: Any) -> bool:
    return typing.get_origin(tp) is list or any(typing.get_origin(a) is list for a in typing.get_args(tp))


def _bracket_lists(arg: str, types: dict[str, Any]) -> str:
    """Accept a bare comma list for a list flag: --perturbations=LB1,LB2 means --perturbations=[LB1,LB2]."""
    name, _, value = arg.lstrip("-").partition("=")
    if name in types and _is_list(types[name]) and value and not value.startswith("["):
        return f"--{name}=[{value}]"
    return arg


def _value_error(message: str) -> str:
    """draccus's "`robot`: ...: `camera`: Couldn't parse 'x' into a bool" as "--robot.camera: couldn't parse ..."."""
    fields = re.findall(r"`([\w.]+)`: ", message)
    if not fields:
        return f"invalid flag value: {message}; see --help"
    detail = message.rsplit("`: ", 1)[1]
    typed = re.search(r"value=(.*?) into field .* of type (.*?)\. Underlying", detail)
    if typed is not None:  # a dict or other structured value
        detail = f"could not read {typed.group(1)} as {typed.group(2)}"
    elif "Couldn't parse" in detail:
        detail = detail.rsplit(": ", 1)[-1]
    return f"--{'.'.join(fields)}: {detail[0].lower()}{detail[1:]}; see --help for the value it takes"


def _unknown(name: str, known: set[str]) -> ConfigError:
    close = difflib.get_close_matches(name, sorted(known), n=1)
    hint = f"did you mean --{close[0]}?" if close else "see --help for the flags this command takes"
    return ConfigError(f"unknown flag --{name}; {hint}")


def parse_config[T](cls: type[T], argv: list[str] | None = None) -> T:
    """Parse LeRobot-style `--name=value` flags, turning any mistake into a one-line ConfigError."""
    argv = join_values(list(sys.argv[1:] if argv is None else argv))
    types = flag_types(cls)
    known = set(types) | {"config_path"}
    for arg in argv:
        if not arg.startswith("-"):
            raise ConfigError(f"unexpected argument {arg!r}; flags look like --name=value (see --help)")
        name = arg.lstrip("-").split("=", 1)[0]
        if name not in known and not name.startswith("robot."):  # robot fields depend on --robot.type
            raise _unknown(name, known)
        if "=" not in arg:
            raise ConfigError(f"--{name} needs a value, e.g. --{name}=true or --{name} true")
    argv = [_bracket_lists(arg, types) for arg in argv]
    try:
        return draccus.parse(config_class=cls, args=argv)
    except SystemExit:
        raise
    except Exception as error:  # draccus reports bad values with multi-line messages
        raise ConfigError(_value_error(" ".join(str(error).split()))) from None


def _type_name(tp: Any) -> str:
    args = [a for a in typing.get_args(tp) if a is not type(None)]
    if typing.get_origin(tp) in (typing.Union, __import__("types").UnionType) and len(args) == 1:
        tp = args[0]
    if typing.get_origin(tp) is list:
        return "A,B,..."
    if typing.get_origin(tp) is dict:
        return "JSON"
    if tp is Path:
        return "PATH"
    return getattr(tp, "__name__", str(tp)).upper()


def _describe(value: Any) -> str:
    if value is None:
        return "none"
    if isinstance(value, list | tuple | dict) and not value:
        return "none"
    return str(value).lower() if isinstance(value, bool) else str(value)


def flag_lines(cls: type, prefix: str, skip: tuple[str, ...] = ()) -> list[str]:
    """One entry per flag: `--name TYPE`, then its comment, with the default unless the comment states it."""
    lines: list[str] = []
    hints = typing.get_type_hints(cls)
    for f in dataclasses.fields(cls):
        if f.name in skip or not f.init:
            continue
        default = _default(f)
        if dataclasses.is_dataclass(default):
            lines += flag_lines(type(default), f"{prefix}{f.name}.")
            continue
        default = f.metadata.get("help_default", default)  # what None stands for, where that is a name
        doc = get_attribute_docstring(cls, f.name)
        text = " ".join((doc.comment_above or doc.comment_inline or doc.docstring_below).split())
        if default is dataclasses.MISSING:
            text = f"{text} (required)".strip()
        elif "default" not in text.lower():
            text = f"{text} (default: {_describe(default)})".strip()
        lines.append(f"  --{prefix}{f.name} {_type_name(hints[f.name])}")
        lines += textwrap.wrap(text, WIDTH, initial_indent=" " * 6, subsequent_indent=" " * 6)
    return lines


def help_text(cls: type, command: str, robot_type: str | None) -> str:
    """The command's flags in full, then the chosen robot's fields, or the robot types to choose from."""
    from lerobot.robots import RobotConfig

    lines = [f"usage: {command} [--flag=value | --flag value] ...", "", (cls.__doc__ or "").strip(), ""]
    lines += flag_lines(cls, "", skip=("robot",))
    known = sorted(RobotConfig.get_known_choices())
    if robot_type in known:
        lines += ["", f"--robot.type={robot_type} settings:"]
        lines += flag_lines(RobotConfig.get_choice_class(robot_type), "robot.", skip=("type",))
    else:
        robot = get_attribute_docstring(cls, "robot").comment_above
        lines += [
            "",
            "  --robot.type TYPE",
            *textwrap.wrap(" ".join(robot.split()), WIDTH, initial_indent=" " * 6, subsequent_indent=" " * 6),
        ]
        lines += textwrap.wrap(f"one of: {', '.join(known)}", WIDTH, initial_indent=" " * 6, subsequent_indent=" " * 6)
        lines += ["      Add --robot.type=TYPE to --help for that robot's --robot.* settings."]
    return "\n".join(lines)


def wants_help(argv: list[str]) -> bool:
    return any(arg in HELP for arg in argv)


def robot_type(argv: list[str]) -> str | None:
    given = [arg.split("=", 1)[1] for arg in argv if arg.startswith("--robot.type=")]
    return given[-1] if given else None
