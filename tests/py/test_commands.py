"""Every Python command of tools/pyproject.toml: its module is named after
it, every option says what it does (help text), and a bad command line
exits with 2 as the C tools do (1 is a failure at run time, 0 success)."""

import argparse
import importlib
import re
from pathlib import Path

import pytest

from conftest import REPO_ROOT


# The commands only the scripts and the tests run, as python -m rsm_tools.NAME.
INTERNAL = [("rsm-m4", "rsm_tools.m4", "main"), ("rsm-sweep", "rsm_tools.sweep", "main"),
            ("rsm-fullchecks", "rsm_tools.fullchecks", "main"), ("rsm-demo", "rsm_tools.demo", "main")]


def commands():
    text = (REPO_ROOT / "tools" / "pyproject.toml").read_text(encoding="utf-8")
    block = text.split("[project.scripts]", 1)[1].split("\n[", 1)[0]
    return re.findall(r'^([a-z0-9-]+)\s*=\s*"([a-z0-9_.]+):([a-z_]+)"', block, re.M) + INTERNAL


class _Parsed(Exception):
    pass


def parsers_of(module, func):
    """The argparse parsers main() builds (with their sub-commands'), caught
    as it parses its arguments; nothing is run."""
    seen = []
    real = argparse.ArgumentParser.parse_args

    def catch(self, args=None, namespace=None):
        seen.append(self)
        raise _Parsed()

    argparse.ArgumentParser.parse_args = catch
    try:
        with pytest.raises(_Parsed):
            getattr(module, func)([])
    finally:
        argparse.ArgumentParser.parse_args = real
    out = []
    todo = list(seen)
    while todo:
        p = todo.pop()
        out.append(p)
        for a in p._actions:
            if isinstance(a, argparse._SubParsersAction):
                todo.extend(a.choices.values())
    return out


def test_the_commands_are_listed():
    names = [c for c, _, _ in commands()]
    assert "rsm-bench" in names and "rsm-evaluate" in names and "rsm-record" in names and len(names) >= 12


@pytest.mark.parametrize("command,module,func", commands())
def test_module_is_named_after_the_command(command, module, func):
    """rsm-NAME is rsm_tools.NAME (rsm-bench-report: rsm_tools.bench.report),
    and the command calls itself so."""
    assert module == "rsm_tools." + command[len("rsm-"):].replace("-", "."), (command, module)
    mod = importlib.import_module(module)
    assert all(p.prog.split()[0] == command for p in parsers_of(mod, func)), command


@pytest.mark.parametrize("command,module,func", commands())
def test_every_option_has_help(command, module, func):
    mod = importlib.import_module(module)
    missing = []
    for p in parsers_of(mod, func):
        for a in p._actions:
            if isinstance(a, (argparse._HelpAction, argparse._SubParsersAction)):
                continue
            if not a.help or a.help == argparse.SUPPRESS:
                missing.append(f"{p.prog}: {'/'.join(a.option_strings) or a.dest}")
    assert not missing, missing


@pytest.mark.parametrize("command,module,func", commands())
def test_a_bad_command_line_exits_2(command, module, func, capsys):
    mod = importlib.import_module(module)
    with pytest.raises(SystemExit) as e:
        getattr(mod, func)(["--no-such-option-anywhere"])
    assert e.value.code == 2
