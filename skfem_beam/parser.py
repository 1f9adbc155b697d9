"""The parser of every command's line: argparse, but a bad flag gives one line on stderr
and exit code 2 (``errors.EXIT_INPUT``), not a usage block.  ``cli`` builds the scenes'
flags on it; ``results.export_main`` and the scene file's subcommands use it too."""
import argparse
import re
import tomllib

from .errors import EXIT_INPUT


# a negative number argparse takes for a value, not a flag: its own "-1", "-.5", and also
# "-1e-3" ("--dt -1e-3" read "expected one argument", "--v0 -1e-1" was unusable), and a
# list that starts with one ("--values -5,10" read "expected one argument" too)
_NUMBER = r"(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?"
NEGATIVE_NUMBER = re.compile(rf"^-{_NUMBER}(\s*,\s*-?{_NUMBER})*$")


class Parser(argparse.ArgumentParser):
    """argparse, but a bad flag gives one line on stderr, not a usage block, and a negative
    number in exponent form is a value."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = NEGATIVE_NUMBER

    def error(self, message):
        self.exit(EXIT_INPUT, f"{self.prog}: error: {message}\n")


class Defaults(argparse.ArgumentDefaultsHelpFormatter):
    """--help with each flag's default, once: none where the help names it already or
    where the default is None (the help says what not giving it means)."""

    def _get_help_string(self, action):
        if action.default is None or "default" in (action.help or ""):
            return action.help
        return super()._get_help_string(action)


def count(text: str) -> int:
    """An argparse type: a whole number ≥ 1 (a repeat, a cycle count, a mesh size)."""
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number ≥ 1")
    return value


def counts(text: str) -> list[int]:
    """An argparse type: comma-separated whole numbers ≥ 1 (``25,50,100``)."""
    return [count(s) for s in text.split(",")]


def positives(text: str) -> list[float]:
    """An argparse type: comma-separated numbers > 0 (``0.4,0.04``)."""
    out = []
    for s in text.split(","):
        try:
            value = float(s)
        except ValueError:
            value = 0.0
        if not value > 0 or value == float("inf"):
            raise argparse.ArgumentTypeError(f"{s!r} is not a finite number > 0")
        out.append(value)
    return out


def made_folder(text: str):
    """An argparse type: a study's --out folder, made now, so that a bad one is refused
    before the study computes (it failed at the end, exit 3, the work lost)."""
    from pathlib import Path
    path = Path(text)
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise argparse.ArgumentTypeError(f"{text!r}: cannot make the folder ({e.strerror})")
    return path


def about(doc: str) -> str:
    """A command's --help description: its module docstring's first paragraph, joined
    (its first line alone stopped mid-sentence)."""
    return " ".join((doc or "").strip().split("\n\n")[0].split())


def toml_value(text: str):
    """``text`` as a TOML value (number, boolean, array, inline table, quoted string);
    a bare word is a string (``--set ends.right=free``)."""
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text


def set_pair(assignment: str) -> tuple[str, object]:
    """A ``--set KEY=VALUE`` as (KEY dotted, ``obstacles[0].x`` as ``obstacles.0.x``,
    VALUE read as TOML)."""
    key, _, text = assignment.partition("=")
    return re.sub(r"\[(\d+)\]", r".\1", key.strip()), toml_value(text.strip())


def same_sets(a, b) -> bool:
    """Whether two lists of ``--set`` flags set the same values however written (a key
    dotted or indexed, 0.30 or 0.3), in any order where no key is set twice or inside
    another (then their order decides, and is compared too)."""
    pa, pb = [set_pair(x) for x in a or ()], [set_pair(x) for x in b or ()]
    if pa == pb:
        return True
    keys = [k for k, _ in pa]
    nested = any(i != j and (k == q or q.startswith(k + "."))
                 for i, k in enumerate(keys) for j, q in enumerate(keys))
    return not nested and len(pa) == len(pb) and \
        sorted(pa, key=lambda p: p[0]) == sorted(pb, key=lambda p: p[0])
