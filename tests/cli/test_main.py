"""The `ehlfoam` front end: --version, every subcommand's help ending with examples that are
valid commands on existing files, light imports for the help, OPENBLAS_NUM_THREADS set by
main() and not on import, `python -m ehlfoam`."""

from __future__ import annotations

import argparse
import json
import os
import re
import shlex
import subprocess
import sys
from importlib.metadata import version
from pathlib import Path

import pytest

from ehlfoam.cli.main import COMMANDS, build_parser, main

ROOT = Path(__file__).resolve().parents[2]
EHLFOAM = [str(Path(sys.executable).parent / "ehlfoam")]
ENV_ASSIGNMENT = re.compile(r"[A-Z_][A-Z0-9_]*=\S*")
HEAVY = ("numpy", "scipy", "pyvista", "vtk", "foamlib", "gmsh", "dask", "matplotlib",
         "pydantic", "numba")


def subparsers(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    [action] = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return action.choices


def examples(help_text: str) -> list[str]:
    """The command lines after the help's last 'example:' line."""
    tail = help_text.rsplit("\nexample:\n", 1)[1]
    return [line.strip() for line in tail.splitlines() if line.startswith("  ")]


def test_version_is_the_installed_packages(capsys):
    assert main(["--version"]) == 0
    assert capsys.readouterr().out.strip() == f"ehlfoam {version('ehlfoam')}"
    proc = subprocess.run([*EHLFOAM, "--version"], capture_output=True, text=True)
    assert proc.returncode == 0 and proc.stdout.strip() == f"ehlfoam {version('ehlfoam')}"


def test_every_subcommand_is_listed_and_has_its_module():
    names = list(subparsers(build_parser()))
    assert names == ["doctor", "precalc", "thin-film", "case", "run", "band", "snapshot", "report",
                     "batch", "foam"]
    assert [m.__name__.rsplit(".", 1)[1] for m in COMMANDS] == [n.replace("-", "_") for n in names]


@pytest.mark.parametrize("name", ["doctor", "precalc", "case", "run", "band", "snapshot",
                                  "report", "batch", "foam", None])
def test_help_ends_with_examples_that_are_valid_commands_on_existing_files(name):
    parser = build_parser()
    help_text = (parser if name is None else subparsers(parser)[name]).format_help()
    lines = examples(help_text)
    assert lines, help_text
    for k, line in enumerate(lines):
        words = shlex.split(line)
        while words and ENV_ASSIGNMENT.fullmatch(words[0]):
            words.pop(0)
        assert words[0] == "ehlfoam", line
        if words[1:] == ["COMMAND", "--help"]:
            continue
        assert name is None or k > 0 or words[1] == name, line   # the first: the command
        args = build_parser().parse_args(words[1:])      # a valid command line
        assert callable(args.func), line
        for word in words:
            for path in re.findall(r"examples/\S+\.toml", word):
                assert (ROOT / path).is_file(), (line, path)


def test_the_help_loads_no_heavy_library_and_import_sets_no_environment():
    code = ("import json, os, sys; before = dict(os.environ)\n"
            "from ehlfoam.cli.main import main\n"
            "changed = dict(os.environ) != before\n"
            "codes = [main([c, '--help']) for c in ('doctor', 'precalc', 'case', 'run', "
            "'band', 'snapshot', 'report', 'batch', 'foam')]\n"
            f"print(json.dumps([changed, codes, [m for m in {HEAVY!r} if m in sys.modules], "
            "os.environ.get('OPENBLAS_NUM_THREADS')]))\n")
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    proc = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                          text=True)
    assert proc.returncode == 0, proc.stderr
    changed, codes, heavy, openblas = json.loads(proc.stdout.strip().splitlines()[-1])
    assert not changed and codes == [0] * 9 and heavy == []
    assert openblas == "1"          # main() sets it, before any command loads numpy
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env={**env, "OPENBLAS_NUM_THREADS": "3"})
    assert json.loads(proc.stdout.strip().splitlines()[-1])[3] == "3"    # the user's choice


def test_python_dash_m_ehlfoam_is_the_command(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "ehlfoam", "case", str(tmp_path / "none.toml"),
                           "--out", str(tmp_path / "out")], capture_output=True, text=True)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.startswith("ehlfoam case: ") and "none.toml" in proc.stderr
    assert not (tmp_path / "out").exists()
    proc = subprocess.run([sys.executable, "-m", "ehlfoam", "nonsense"], capture_output=True,
                          text=True)
    assert proc.returncode == 2 and "invalid choice: 'nonsense'" in proc.stderr


def test_a_set_without_a_value_is_bad_input(tmp_path, capsys):
    assert main(["case", "--out", str(tmp_path / "out"), "--set", "mesh.resolution"]) == 2
    assert "--set 'mesh.resolution': expected KEY=VALUE" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()
