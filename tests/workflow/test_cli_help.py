"""Every argument of every `ballaststudy` subcommand says what it is (`--help` is the CLI's
reference; the user guide's command pages are generated from the same parser)."""
import argparse

from ballaststudy.cli import build_parser


def arguments(parser, command="ballaststudy"):
    """[(command, argument, help)] of the parser and its subcommands."""
    out = []
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                out += arguments(sub, f"{command} {name}")
        elif not isinstance(action, argparse._HelpAction):
            out.append((command, "/".join(action.option_strings) or action.dest, action.help))
    return out


def test_every_argument_has_help():
    found = arguments(build_parser())
    missing = [f"{command} {name}" for command, name, text in found if not text]
    assert len(found) > 100 and not missing, missing
