"""Command-line flags over a draccus config: `--name=value` or `--name value`, one-line errors that suggest the flag
meant, and a --help that lists the command's own flags first and a robot's fields only for the chosen --robot.type;
and the scripts' argparse parser, whose errors are one line too."""

from __future__ import annotations

import argparse
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

from lerobot_contrast.contrast.errors import UserError

HELP = ("--help", "-h")


class ScriptParser(argparse.ArgumentParser):
    """argparse for the scripts under scripts/: a bad flag is one line, `error: ...`, and exit status 2."""

    def error(self, message: str) -> typing.NoReturn:
        self.exit(2, f"error: {message}\n")


class ConfigError(UserError):
    """A flag or setting that cannot make a sound run."""


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


def flag_names(cls: type, prefix: str = "") -> dict[str, bool]:
    """Every flag of `cls` and whether it takes true or false, read without resolving the fields' types (the robot
    field's would load LeRobot and torch), so that a mistyped name is answered at once."""
    names: dict[str, bool] = {}
    for f in dataclasses.fields(cls):
        default = _default(f)
        if dataclasses.is_dataclass(default):
            names |= flag_names(type(default), prefix + f.name + ".")
        else:
            names[prefix + f.name] = f.type in (bool, "bool")
    return names


def bool_flags(cls: type) -> set[str]:
    """The flags of `cls` that take true or false (alone, they mean true)."""
    return {name for name, boolean in flag_names(cls).items() if boolean}


def _default(f: dataclasses.Field) -> Any:
    return f.default_factory() if f.default_factory is not dataclasses.MISSING else f.default


BOOL_WORDS = ("true", "false")


def join_values(argv: list[str], booleans: set[str] = frozenset()) -> list[str]:
    """`--name value` as `--name=value`, the form LeRobot's own commands also accept. A flag in `booleans` given
    alone means `=true`, so it takes the next argument only when that is true or false."""
    out: list[str] = []
    args = list(argv)
    while args:
        arg = args.pop(0)
        name = arg[2:]
        if arg.startswith("--") and "=" not in arg and arg not in HELP:
            takes_next = args and not args[0].startswith("--")
            if name in booleans and not (takes_next and args[0].lower() in BOOL_WORDS):
                out.append(f"{arg}=true")
            elif takes_next:
                out.append(f"{arg}={args.pop(0)}")
            else:
                out.append(arg)
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
    """The nearest valid names; with none near, the valid names of the same group (--policy.*, --robot.*)."""
    close = difflib.get_close_matches(name, sorted(known), n=3, cutoff=0.7)
    group = name.rpartition(".")[0]
    siblings = sorted(k for k in known if k.rpartition(".")[0] == group) if group else []
    if close:
        hint = f"did you mean {' or '.join('--' + c for c in close)}?"
    elif siblings:
        hint = f"--{group}.* takes {', '.join('--' + s for s in siblings)}"
    else:
        hint = "see --help for the flags this command takes"
    return ConfigError(f"unknown flag --{name}; {hint}")


def _robot_flags(argv: list[str]) -> set[str]:
    """The --robot.* names the chosen --robot.type takes (none until one is chosen)."""
    chosen = robot_type(argv)
    if chosen is None:
        return set()
    from lerobot.robots import RobotConfig

    if chosen not in RobotConfig.get_known_choices():
        return {"robot.type"}
    return {"robot.type", *flag_types(RobotConfig.get_choice_class(chosen), "robot.")}


def check_names(argv: list[str], types: dict[str, Any], robots: bool = True) -> None:
    """Every flag is one the command (or its chosen robot) takes, with a value; else one line naming it.
    `robots=False` leaves --robot.* names unchecked, for a check before the robot types are registered."""
    known = set(types) | {"config_path"}
    robot = _robot_flags(argv) if "robot" in types and robots else set()
    for arg in argv:
        if not arg.startswith("-"):
            raise ConfigError(f"unexpected argument {arg!r}; flags look like --name=value (see --help)")
        name = arg.lstrip("-").split("=", 1)[0]
        chosen = robot or robot_type(argv) is not None or name == "robot.type"
        if name.startswith("robot.") and "robot" in types and not chosen:
            raise ConfigError(f"--{name} needs --robot.type=TYPE, the robot whose setting it is")
        if name.startswith("robot.") and "robot" in types and not robots:
            continue
        if name.startswith("robot.") and "robot" in types and name not in robot:
            raise _unknown(name, robot | {k for k in known if not k.startswith("robot")})
        if name not in known | robot:
            raise _unknown(name, known)
        if "=" not in arg:
            raise ConfigError(f"--{name} needs a value, e.g. --{name}=VALUE or --{name} VALUE")


def parse_config[T](cls: type[T], argv: list[str] | None = None, positional: str | None = None) -> T:
    """Parse LeRobot-style `--name=value` (or `--name value`) flags, turning any mistake into a one-line ConfigError.
    `positional`: the field that arguments without a name fill (a list field takes several)."""
    types = flag_types(cls)
    argv = join_values(list(sys.argv[1:] if argv is None else argv), bool_flags(cls))
    given = [arg for arg in argv if not arg.startswith("-")] if positional else []
    argv = [arg for arg in argv if arg not in given]
    if len(given) > 1 and not _is_list(types[positional]):
        raise ConfigError(f"unexpected argument {given[1]!r}; give one {positional.upper()} (see --help)")
    check_names(argv, types)
    argv = [_bracket_lists(arg, types) for arg in argv]
    try:
        cfg = draccus.parse(config_class=cls, args=argv)
    except SystemExit:
        raise
    except Exception as error:  # draccus reports bad values with multi-line messages
        raise ConfigError(_value_error(" ".join(str(error).split()))) from None
    if given:
        setattr(cfg, positional, _positional_value(types[positional], given))
    return cfg


def _positional_value(tp: Any, given: list[str]) -> Any:
    if _is_list(tp):
        return given
    return Path(given[0]) if tp is Path or Path in typing.get_args(tp) else given[0]


def usage_text(cls: type, usage: str, skip: tuple[str, ...] = ()) -> str:
    """Every command's --help: its usage line, what it does, then its flags, each with its default."""
    return "\n".join([f"usage: {usage}", "", (cls.__doc__ or "").strip(), "", *flag_lines(cls, "", skip)])


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


# Groups of flags that --help shows only for the operators they serve, else as one line.
OPERATOR_GROUPS = {
    "arm": (("arm",), "how the arm stages and labels: add --operator=arm to --help"),
    "person": (("console", "arm"), "the person's phone page and messages: add --operator=console to --help"),
}


def help_text(cls: type, command: str, robot_type: str | None, operator: str | None = None) -> str:
    """The command's flags in full (groups for an operator, as `--arm.*`, only with that `operator`), then the chosen
    robot's fields, or the robot types to choose from."""
    from lerobot.robots import RobotConfig

    lines = [f"usage: {command} [--flag=value | --flag value] ...", "", (cls.__doc__ or "").strip(), ""]
    fields = {f.name for f in dataclasses.fields(cls)}
    hidden = [name for name, (shown, _) in OPERATOR_GROUPS.items() if name in fields and operator not in shown]
    lines += flag_lines(cls, "", skip=("robot", *hidden))
    lines += [f"  {'--' + name + '.*':<12}{OPERATOR_GROUPS[name][1]}" for name in hidden]
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
