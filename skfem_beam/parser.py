"""The parser of every command's line: argparse, but a bad flag gives one line on stderr
and exit code 2 (``errors.EXIT_INPUT``), not a usage block.  ``cli`` builds the scenes'
flags on it; ``results.export_main`` and the scene file's subcommands use it too."""
import argparse

from .errors import EXIT_INPUT


class Parser(argparse.ArgumentParser):
    """argparse, but a bad flag gives one line on stderr, not a usage block."""

    def error(self, message):
        self.exit(EXIT_INPUT, f"{self.prog}: error: {message}\n")


class Defaults(argparse.ArgumentDefaultsHelpFormatter):
    """--help with each flag's default, once: none where the help names it already or
    where the default is None (the help says what not giving it means)."""

    def _get_help_string(self, action):
        if action.default is None or "default" in (action.help or ""):
            return action.help
        return super()._get_help_string(action)
