"""The one error path of the command line (:mod:`ehlfoam.cli.failures`): each kind of
exception to its exit code and one line naming what, its value and why; ``--debug`` re-raises;
the exit codes distinct and documented in one table (``ehlfoam --help``, docs/cli.md)."""

from __future__ import annotations

import argparse
import errno
import json
import re
import shutil
from pathlib import Path

import pytest
from pydantic import BaseModel, ConfigDict, ValidationError

from ehlfoam.case.writer import CaseExists
from ehlfoam.cli.common import (EXIT_BAD_INPUT, EXIT_CODES, EXIT_FAILURE, EXIT_INTERNAL,
                                EXIT_INTERRUPTED, EXIT_NOT_CONVERGED, EXIT_OK)
from ehlfoam.cli.failures import explain, one_line, run_command
from ehlfoam.cli.main import build_parser, main
from ehlfoam.errors import SpecError
from ehlfoam.foam.runtime import FoamConfigError, FoamError

ROOT = Path(__file__).resolve().parents[2]


def _case_args(out: str = "runs/x", spec: str = "specs/a.toml"):
    """The parsed arguments of ``ehlfoam case SPEC --out OUT`` and the case parser."""
    parser = build_parser()
    args = parser.parse_args(["case", spec, "--out", out])
    [action] = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return args, action.choices["case"]


class _Strict(BaseModel):
    model_config = ConfigDict(strict=True)
    load: float = 1.0


def _validation_error() -> ValidationError:
    with pytest.raises(ValidationError) as info:
        _Strict(load=True)
    return info.value


def _foam_parse_error() -> Exception:
    from foamlib import FoamFile

    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "controlDict"
        path.write_text("garbage {{{ ;;\n")
        with pytest.raises(ValueError) as info:
            FoamFile(path).as_dict()
    return info.value


def _json_error() -> Exception:
    with pytest.raises(json.JSONDecodeError) as info:
        json.loads("{oops")
    return info.value


def _unicode_error() -> Exception:
    with pytest.raises(UnicodeDecodeError) as info:
        bytes([0xff, 0xfe]).decode("utf-8")
    return info.value


CASES = [
    # (exception, exit code, the message's regex)
    (SpecError("invalid case spec: contact.load = True: a boolean is not a number"), 2,
     r"^invalid case spec: contact.load = True"),
    (ValueError("size(x, y) asks for about 5.6e+07 quads"), 2, r"^size\(x, y\) asks"),
    (_validation_error(), 2, r"^invalid _Strict: load = True: Input should be a valid number$"),
    (_json_error(), 2, r"^not valid JSON: Expecting property name"),
    (_foam_parse_error(), 2,
     r"^not a valid OpenFOAM dictionary: line 1, column \d+: expected keyword"),
    (_unicode_error(), 2, r"should be UTF-8 text is not \(byte 0"),
    (FileNotFoundError(errno.ENOENT, "No such file", "specs/a.toml"), 2,
     r"^SPEC specs/a.toml: no such file or directory$"),
    (IsADirectoryError(errno.EISDIR, "Is a directory", "specs/a.toml"), 2,
     r"^SPEC specs/a.toml: is a directory$"),
    (NotADirectoryError(errno.ENOTDIR, "Not a directory", "runs/x"), 2,
     r"^--out runs/x: not a directory$"),
    (PermissionError(errno.EACCES, "Permission denied", "runs/x/system/controlDict"), 2,
     r"^--out runs/x: permission denied \(runs/x/system/controlDict\)$"),
    (OSError(errno.EROFS, "Read-only file system", "runs/.x.abc123/constant"), 2,
     r"^--out runs/x: read-only file system$"),          # the temporary sibling: --out's
    (OSError(errno.ENOSPC, "No space left on device"), 2,   # no file name: the output's
     r"^--out runs/x: no space left on device$"),
    (OSError(errno.ENOSPC, "No space left on device", "/elsewhere/f"), 2,
     r"^/elsewhere/f: no space left on device$"),
    (shutil.Error([("/cache/p/solution.npz", "runs/.x.q1/precalc/solution.npz",
                    "[Errno 28] No space left on device")]), 2,
     r"^--out runs/x: no space left on device$"),
    (CaseExists("output folder runs/x exists and is not empty (use --overwrite)"), 2,
     r"^output folder runs/x exists"),
    (OSError(errno.EIO, "Input/output error", "runs/x/log"), 1,
     r"^--out runs/x: input/output error \(runs/x/log\)$"),
    (FoamConfigError("EHLFOAM_FOAM = 'bogus': valid are embedded, native, prefix"), 2,
     r"^configuration error: EHLFOAM_FOAM"),
    (FoamError("interFoam failed with exit code 1 in case runs/x"), 1, r"^interFoam failed"),
    (MemoryError(), 1, r"^out of memory"),
    (KeyboardInterrupt(), 130, r"^interrupted$"),
    (RuntimeError("boom\nsecond line"), 70,
     r"^internal error: RuntimeError: boom second line \(a bug; `ehlfoam --debug case \.\.\.`"),
]


@pytest.mark.parametrize("exc, code, pattern", CASES,
                         ids=[f"{type(c[0]).__name__}-{k}" for k, c in enumerate(CASES)])
def test_each_kind_of_error_has_its_code_and_one_line(exc, code, pattern):
    args, parser = _case_args()
    got, message = explain(exc, "case", args, parser)
    assert got == code, message
    assert "\n" not in message and re.search(pattern, message), message


def test_one_line_joins_lines():
    assert one_line("a\n   b\n\nc ") == "a b c"


def test_run_command_prints_one_line_or_reraises_with_debug(capsys):
    def boom(args):
        raise SpecError("invalid case spec: contact.load = True\nsecond")

    args = argparse.Namespace(func=boom)
    assert run_command(args, "case") == EXIT_BAD_INPUT
    assert capsys.readouterr().err == "ehlfoam case: invalid case spec: contact.load = True second\n"
    with pytest.raises(SpecError):
        run_command(args, "case", debug=True)
    args.func = lambda a: (_ for _ in ()).throw(KeyboardInterrupt())
    assert run_command(args, "case", debug=True) == EXIT_INTERRUPTED      # no traceback
    assert capsys.readouterr().err == ""


def test_debug_is_a_global_option_that_reraises(tmp_path, capsys):
    argv = ["case", "--out", str(tmp_path / "c"), "--set", "contact.load=true"]
    assert main(argv) == EXIT_BAD_INPUT
    assert capsys.readouterr().err.count("\n") == 1
    with pytest.raises(SpecError, match="contact.load = True"):
        main(["--debug", *argv])
    assert not (tmp_path / "c").exists()


def test_the_exit_codes_are_distinct_and_documented_in_one_table():
    codes = [c for c, _, _ in EXIT_CODES]
    assert len(set(codes)) == len(codes)
    assert {EXIT_OK, EXIT_FAILURE, EXIT_BAD_INPUT, EXIT_NOT_CONVERGED, EXIT_INTERNAL,
            EXIT_INTERRUPTED} == set(codes)
    help_text = build_parser().format_help()
    page = (ROOT / "docs" / "cli.md").read_text()
    rows = re.findall(r"^\| (\d+) \| ([^|]+) \| ([^|]+) \|$", page, re.M)
    assert [(int(c), n.strip(), m.strip()) for c, n, m in rows] == list(EXIT_CODES)
    for code, name, _ in EXIT_CODES:
        assert re.search(rf"^  {code}\s+{name}\s", help_text, re.M), (code, help_text)
    assert "docs/cli.md" in (ROOT / "README.md").read_text()
