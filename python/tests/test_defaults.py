"""The campaign defaults are written once (ftsmc_sim::defaults): the CLI's
flags, the Python wrappers and the type stubs must all say the same."""

from __future__ import annotations

import ast
import inspect
import re
import subprocess
from pathlib import Path

import ftsmc
from ftsmc import _ftsmc

DEFAULTS = _ftsmc.DEFAULTS
STUB = Path(ftsmc.__file__).with_name("_ftsmc.pyi")


def test_the_library_defaults_are_what_the_docs_say() -> None:
    assert DEFAULTS == {
        "montecarlo_runs": 100,
        "compare_runs": 100,
        "compare_max_runs": 1000,
        "compare_batch": 50,
        "tune_budget": 2000,
        "falsify_budget": 200,
        "failure_probability_budget": 2000,
        "confidence": 0.95,
    }


def test_the_python_wrappers_take_the_library_defaults() -> None:
    cases = [
        (ftsmc.compare, "runs", "compare_runs"),
        (ftsmc.compare, "max_runs", "compare_max_runs"),
        (ftsmc.compare, "batch", "compare_batch"),
        (ftsmc.compare, "confidence", "confidence"),
        (ftsmc.tune, "budget", "tune_budget"),
        (ftsmc.falsify, "budget", "falsify_budget"),
        (ftsmc.failure_probability, "budget", "failure_probability_budget"),
        (ftsmc.failure_probability, "confidence", "confidence"),
    ]
    for function, parameter, key in cases:
        default = inspect.signature(function).parameters[parameter].default
        assert default == DEFAULTS[key] and type(default) is type(DEFAULTS[key]), (function.__name__, parameter)


def test_the_stubs_say_the_library_defaults() -> None:
    tree = ast.parse(STUB.read_text())
    functions = {node.name: node for node in tree.body if isinstance(node, ast.FunctionDef)}
    cases = [
        ("tune_native", "budget", "tune_budget"),
        ("falsify_native", "budget", "falsify_budget"),
        ("failure_probability_native", "budget", "failure_probability_budget"),
        ("failure_probability_native", "confidence", "confidence"),
    ]
    for name, parameter, key in cases:
        args = functions[name].args
        with_defaults = args.args[len(args.args) - len(args.defaults):]
        found = {a.arg: ast.literal_eval(d) for a, d in zip(with_defaults, args.defaults)}
        assert found[parameter] == DEFAULTS[key], (name, parameter, found[parameter])


def _help(cli: Path, command: str) -> str:
    done = subprocess.run([str(cli), command, "--help"], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    return done.stdout


def _flag_default(text: str, flag: str) -> str:
    """The `[default: …]` clap prints under `flag` in a long help."""
    block = text.split(f"{flag} <", 1)[1].split("\n  -", 1)[0]
    found = re.search(r"\[default: ([^\]]+)\]", block)
    assert found, f"{flag}: no default in {block!r}"
    return found.group(1)


def test_the_cli_flags_take_the_library_defaults(cli: Path) -> None:
    compare = _help(cli, "compare")
    assert int(_flag_default(compare, "--runs")) == DEFAULTS["compare_runs"]
    assert float(_flag_default(compare, "--confidence")) == DEFAULTS["confidence"]
    # The two defaults that apply only with --until-decided are stated in words.
    assert f"default {DEFAULTS['compare_max_runs']})" in compare
    assert f"default {DEFAULTS['compare_batch']})" in compare
    assert int(_flag_default(_help(cli, "montecarlo"), "--runs")) == DEFAULTS["montecarlo_runs"]
    assert int(_flag_default(_help(cli, "tune"), "--budget")) == DEFAULTS["tune_budget"]
    fp = _help(cli, "failure-probability")
    assert int(_flag_default(fp, "--budget")) == DEFAULTS["failure_probability_budget"]
    assert float(_flag_default(fp, "--confidence")) == DEFAULTS["confidence"]
    assert f"else {DEFAULTS['falsify_budget']})" in _help(cli, "falsify")
