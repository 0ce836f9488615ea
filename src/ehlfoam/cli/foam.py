"""``ehlfoam foam APP [ARGS...]``: any OpenFOAM application through the configured runtime.

The application runs in the working folder (``-case DIR`` works as OpenFOAM takes it) with the
command prefix and environment of :meth:`ehlfoam.foam.runtime.FoamRuntime.from_environment`,
its arguments passed as a list (no shell) and its output streamed as it comes.

Exit codes: the application's own (128 + N when signal N ended it); 2 when it cannot start:
APP is not a plain application name, the runtime does not have it, or the runtime is not
installed or configured.
"""

from __future__ import annotations

import argparse
import difflib
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from ehlfoam.cli.common import EXIT_BAD_INPUT, EXIT_OK, add_command

if TYPE_CHECKING:
    from ehlfoam.foam.runtime import FoamRuntime

#: a plain application name: letters, digits, '_', '-', '.'; no path
APP_NAME = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.-]*")
#: the embedded runtime's record of the files Debian's openfoam package installed
EMBEDDED_PACKAGE_LIST = "var/lib/dpkg/info/openfoam.list"


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register ``ehlfoam foam``."""
    p = add_command(
        subparsers, "foam", help="run an OpenFOAM application (checkMesh, foamToVTK, ...) "
                                 "through the configured runtime",
        description="Run any OpenFOAM application with the OpenFOAM runtime ehlfoam uses "
                    "(EHLFOAM_FOAM=embedded|native|prefix, see `ehlfoam doctor`), in the "
                    "working folder or in -case DIR, with the application's own options after "
                    "its name. Exit code: the application's; 2 if it cannot start (not a plain "
                    "name, not in the runtime, no runtime).",
        examples=["ehlfoam foam checkMesh -case runs/nominal",
                  "ehlfoam foam foamToVTK -case runs/nominal -latestTime",
                  "ehlfoam foam blockMesh -help", "ehlfoam foam --list"])
    p.add_argument("--list", action="store_true",
                   help="list the applications the runtime has (where it can tell)")
    p.add_argument("app", nargs="?", metavar="APP", help="the application, e.g. checkMesh")
    p.add_argument("args", nargs=argparse.REMAINDER, metavar="ARGS",
                   help="the application's arguments, e.g. -case DIR -latestTime")
    p.set_defaults(func=cmd_foam)
    return p


def cmd_foam(args: argparse.Namespace) -> int:
    """Run the application and return its exit code (see the module doc)."""
    from ehlfoam.foam.runtime import FoamRuntime, FoamRuntimeMissing

    runtime = FoamRuntime.from_environment()
    try:
        runtime.ensure_present()
    except FoamRuntimeMissing as err:
        return _bad(str(err))
    if args.list:
        names = applications(runtime)
        if names is None:
            return _bad(f"the {runtime.kind} runtime cannot list its applications "
                        f"({runtime.command_prefix()})")
        print("\n".join(names))
        return EXIT_OK
    if args.app is None:
        return _bad("name the application to run, e.g. ehlfoam foam checkMesh "
                    "(ehlfoam foam --list lists them)")
    if not APP_NAME.fullmatch(args.app):
        return _bad(f"APP = {args.app!r} is not a plain application name (letters, digits, "
                    f"'_', '-', '.'; no path), e.g. checkMesh")
    missing = _not_there(runtime, args.app)
    if missing:
        return _bad(missing)
    return run_application(runtime, args.app, args.args)


def run_application(runtime: FoamRuntime, app: str, args: list[str]) -> int:
    """``app args`` in the working folder with ``runtime``, output to this process's stdout
    and stderr; the application's exit code (128 + N for signal N)."""
    env = runtime.env()
    here = os.getcwd()
    if os.path.realpath(env.get("PWD", "")) != os.path.realpath(here):
        env["PWD"] = here    # OpenFOAM reads PWD, and warns where it is not the folder
    rc = subprocess.run(runtime.command(app, *args), env=env, check=False).returncode
    return 128 - rc if rc < 0 else rc


def applications(runtime: FoamRuntime) -> list[str] | None:
    """The applications ``runtime`` has, sorted; None where it cannot tell (a prefix
    runtime, a native one without ``FOAM_APPBIN``)."""
    if runtime.kind == "embedded":
        listed = Path(runtime.root) / EMBEDDED_PACKAGE_LIST
        if listed.is_file():
            return sorted(line[len("/usr/bin/"):] for line in listed.read_text().splitlines()
                          if line.startswith("/usr/bin/") and line.count("/") == 3)
        return sorted(p.name for p in (Path(runtime.root) / "usr/bin").iterdir())
    appbin = os.environ.get("FOAM_APPBIN")
    if runtime.kind == "native" and appbin and Path(appbin).is_dir():
        return sorted(p.name for p in Path(appbin).iterdir() if os.access(p, os.X_OK))
    return None


def _not_there(runtime: FoamRuntime, app: str) -> str | None:
    """Why ``runtime`` cannot run ``app`` (None: it can, or a prefix runtime, whose wrapper
    alone knows)."""
    if runtime.kind == "native":
        if shutil.which(app, path=runtime.env().get("PATH")):
            return None
        return (f"{app!r} is not on PATH (EHLFOAM_FOAM=native): source your OpenFOAM's "
                f"bashrc, or see `ehlfoam doctor`")
    names = applications(runtime) if runtime.kind == "embedded" else None
    if names is None or app in names:
        return None
    near = difflib.get_close_matches(app, names, n=3)
    return (f"{app!r} is not an application of the embedded OpenFOAM runtime "
            f"({runtime.describe().get('version', runtime.root)})"
            + (f"; did you mean {', '.join(near)}?" if near else ";")
            + f" `ehlfoam foam --list` lists its {len(names)} applications")


def _bad(message: str) -> int:
    print(f"ehlfoam foam: {message}", file=sys.stderr)
    return EXIT_BAD_INPUT
