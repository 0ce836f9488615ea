"""How ehlfoam runs OpenFOAM commands: the one module that knows.

Every OpenFOAM application (blockMesh, interFoam, ...) is started through a
:class:`FoamRuntime`. Three kinds exist, chosen by environment variables
(:meth:`FoamRuntime.from_environment`):

``EHLFOAM_FOAM=embedded`` (default)
    Debian 13 (trixie) OpenFOAM v1912, installed by ``tools/ensure-env`` with
    ``debootstrap`` into ``$EHLFOAM_CACHE/openfoam-trixie`` (default cache
    ``${XDG_CACHE_HOME:-~/.cache}/ehlfoam``). Applications run on the host,
    without a chroot, through the runtime's own dynamic loader::

        DIR/lib64/ld-linux-x86-64.so.2 --library-path DIR/usr/lib:... DIR/usr/bin/APP args

    with ``WM_PROJECT_DIR=DIR/usr/share/openfoam``. The library path is given
    to the loader only; it is never exported in ``LD_LIBRARY_PATH`` (host
    programs would then load Debian 13's libc and fail). Debian 12's own
    build is not used because it computes ``fvc::reconstruct`` wrongly (see
    :func:`check_build`).
``EHLFOAM_FOAM=native``
    Applications found on ``PATH``; ``WM_PROJECT_DIR`` from the environment,
    else ``/usr/share/openfoam``.
``EHLFOAM_FOAM=prefix``
    ``EHLFOAM_FOAM_PREFIX`` is a shell-words command prefix (e.g. a wrapper
    script that sources an OpenFOAM bashrc and execs its arguments); the
    command is ``PREFIX... APP args``, environment unchanged.

Parallel runs: :meth:`FoamRuntime.mpi_command` (the embedded runtime's mpirun
cannot be driven through the loader; it runs in a chroot of the runtime).

Every process started here dies with the thread that started it
(:mod:`ehlfoam.foam.lifetime`: Linux's parent-death signal), and an embedded
parallel run lives in a PID namespace of its own, so that all its ranks die
with it: a SIGKILL of ``ehlfoam run`` leaves no solver behind.
"""

from __future__ import annotations

import math
import os
import re
import shlex
import shutil
import signal
import subprocess
import tempfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

from ehlfoam.foam.lifetime import die_with_parent
from ehlfoam.paths import cache_dir

__all__ = [
    "GOOD_BUILD_MAX_ERROR",
    "BuildCheck",
    "FoamConfigError",
    "FoamError",
    "FoamRuntime",
    "FoamRuntimeMissing",
    "check_build",
    "parse_velocity_error",
]

Kind = Literal["embedded", "native", "prefix"]
KINDS: tuple[str, ...] = ("embedded", "native", "prefix")

#: Folder name of the embedded runtime inside the cache folder.
EMBEDDED_DIRNAME = "openfoam-trixie"
#: Stamp written by tools/ensure-env once the runtime is complete.
EMBEDDED_STAMP = ".ehlfoam-runtime"
#: Loader of the embedded rootfs (relative to its root).
EMBEDDED_LOADER = "lib64/ld-linux-x86-64.so.2"
#: Library folders handed to the loader, in order. In trixie ``lib`` is a
#: symlink to ``usr/lib``, so the last entry duplicates the third and is
#: dropped; only folders that exist are used.
EMBEDDED_LIB_DIRS: tuple[str, ...] = (
    "usr/lib",                     # OpenFOAM's libraries (libOpenFOAM.so, ...)
    "usr/lib/openmpi-system",      # libPstream.so (MPI build), libptscotchDecomp.so
    "usr/lib/x86_64-linux-gnu",    # libc, libstdc++, openmpi, ...
    "lib/x86_64-linux-gnu",
)
DEFAULT_NATIVE_PROJECT_DIR = "/usr/share/openfoam"
#: mpirun and the options every parallel run gets (see FoamRuntime.mpi_command).
MPIRUN: tuple[str, ...] = ("mpirun", "--oversubscribe", "--bind-to", "none")

#: A build passes the pitzDaily check when its error is below this.
#: Good build (Debian 13, 1912.200626-3+b1): 1.14e-4; broken Debian 12 build: 1218.37.
GOOD_BUILD_MAX_ERROR = 1e-2

_PITZDAILY_TEMPLATE = Path(__file__).resolve().parent / "pitzDaily"

_SETUP_HINT = (
    "Run ./Allrun or ./Alltest (they call tools/ensure-env, which installs it), "
    "or set EHLFOAM_FOAM=native (OpenFOAM on PATH) or "
    "EHLFOAM_FOAM=prefix with EHLFOAM_FOAM_PREFIX='your-wrapper' to use your own OpenFOAM."
)


class FoamError(RuntimeError):
    """An OpenFOAM command could not be run or failed."""


class FoamRuntimeMissing(FoamError):
    """The configured OpenFOAM installation is not there."""


class FoamConfigError(FoamError, ValueError):
    """The EHLFOAM_* configuration is invalid (bad input)."""


@dataclass(frozen=True)
class FoamRuntime:
    """A way to run OpenFOAM applications.

    Build one with :meth:`embedded`, :meth:`native`, :meth:`with_prefix` or
    :meth:`from_environment`; then use :meth:`command`, :meth:`env` and
    :meth:`run`.
    """

    kind: Kind
    #: embedded: the rootfs folder (…/openfoam-trixie).
    root: Path | None = None
    #: prefix: the command words put before the application name.
    prefix: tuple[str, ...] = ()
    #: WM_PROJECT_DIR given to the applications (None: leave the environment alone).
    project_dir: Path | None = None

    # ------------------------------------------------------------ factories
    @classmethod
    def embedded(cls, root: str | os.PathLike[str]) -> FoamRuntime:
        """The embedded runtime in ``root``. A root whose path holds what the loader's
        library path splits at (``:``, ``;``) or what OpenFOAM strips from an application's
        path (white space, quotes) cannot run: :class:`FoamConfigError` naming it."""
        root = Path(root).expanduser().absolute()
        bad = sorted({c for c in str(root) if c in ":;\"'" or c.isspace()})
        if bad:
            raise FoamConfigError(
                f"the embedded OpenFOAM's folder {str(root)!r} (EHLFOAM_CACHE/{EMBEDDED_DIRNAME})"
                f" holds {' '.join(repr(c) for c in bad)}: OpenFOAM cannot run from such a path "
                f"(valid: no white space, quotes, ':' or ';'); set EHLFOAM_CACHE to another "
                f"folder")
        return cls(kind="embedded", root=root, project_dir=root / "usr/share/openfoam")

    @classmethod
    def native(cls, project_dir: str | os.PathLike[str] | None = None) -> FoamRuntime:
        return cls(kind="native",
                   project_dir=Path(project_dir or DEFAULT_NATIVE_PROJECT_DIR))

    @classmethod
    def with_prefix(cls, prefix: str | Sequence[str]) -> FoamRuntime:
        words = tuple(shlex.split(prefix) if isinstance(prefix, str) else prefix)
        if not words:
            raise FoamConfigError("EHLFOAM_FOAM=prefix needs a non-empty EHLFOAM_FOAM_PREFIX "
                                  "(e.g. EHLFOAM_FOAM_PREFIX='/opt/of/run-foam')")
        return cls(kind="prefix", prefix=words)

    @classmethod
    def from_environment(cls, environ: Mapping[str, str] | None = None) -> FoamRuntime:
        """The runtime chosen by ``EHLFOAM_FOAM`` (embedded|native|prefix),
        ``EHLFOAM_FOAM_PREFIX``, ``EHLFOAM_CACHE`` and, for native,
        ``WM_PROJECT_DIR``. Raises :class:`FoamConfigError` on bad values;
        does not check that the installation exists (see :meth:`ensure_present`).
        """
        env = os.environ if environ is None else environ
        kind = (env.get("EHLFOAM_FOAM") or "embedded").strip()
        if kind == "embedded":
            return cls.embedded(cache_dir(env) / EMBEDDED_DIRNAME)
        if kind == "native":
            return cls.native(env.get("WM_PROJECT_DIR") or None)
        if kind == "prefix":
            return cls.with_prefix(env.get("EHLFOAM_FOAM_PREFIX", ""))
        raise FoamConfigError(
            f"EHLFOAM_FOAM={kind!r}: expected one of {', '.join(KINDS)}")

    # ------------------------------------------------------------- queries
    def _root(self) -> Path:
        assert self.root is not None, "embedded runtime without root"
        return self.root

    def library_path(self) -> list[str]:
        """embedded: the loader's --library-path folders that exist (deduplicated)."""
        if self.kind != "embedded":
            return []
        dirs: list[str] = []
        seen: set[str] = set()
        for rel in EMBEDDED_LIB_DIRS:
            d = self._root() / rel
            if d.is_dir():
                real = os.path.realpath(d)
                if real not in seen:
                    seen.add(real)
                    dirs.append(str(d))
        if not dirs:  # not installed (yet): show the expected layout
            dirs = [str(self._root() / rel) for rel in EMBEDDED_LIB_DIRS[:3]]
        return dirs

    def app_path(self, app: str) -> str:
        """Where ``app`` is: a file for embedded, a PATH lookup for native,
        the bare name for prefix (the wrapper resolves it)."""
        if "/" in app or not app:
            raise FoamConfigError(f"not an OpenFOAM application name: {app!r}")
        if self.kind == "embedded":
            return str(self._root() / "usr/bin" / app)
        if self.kind == "native":
            return shutil.which(app, path=self.env().get("PATH")) or app
        return app

    def command(self, app: str, *args: str | os.PathLike[str]) -> list[str]:
        """The argv that runs ``app args`` with this runtime."""
        argv = [os.fspath(a) for a in args]
        if self.kind == "embedded":
            root = self._root()
            return [str(root / EMBEDDED_LOADER),
                    "--library-path", ":".join(self.library_path()),
                    self.app_path(app), *argv]
        if self.kind == "native":
            return [app, *argv]
        return [*self.prefix, app, *argv]

    def mpi_command(self, app: str, n_procs: int, case: str | os.PathLike[str],
                    *args: str) -> list[str]:
        """The argv that runs ``app -parallel`` on ``n_procs`` MPI ranks in ``case``.

        native/prefix: ``mpirun --oversubscribe --bind-to none -np N <command> -parallel`` (the
        user's mpirun). ``--bind-to none``: by default Open MPI binds a small run's ranks to
        cores counted from the first, for every mpirun alike, so cases run side by side (a
        batch, ``--jobs``) would share those cores and leave the others idle.
        embedded: Debian 13's mpirun cannot be driven through the loader, so the run happens
        in a chroot of the runtime, in a private mount namespace where the case is
        bind-mounted at ``/mnt`` (the mounts vanish with the process) and a PID namespace of
        its own (``unshare --mount --pid --fork --kill-child``): when ``unshare`` dies, however
        it dies, the kernel kills every process of the run, mpirun's daemon and ranks
        included. Its ``/tmp`` and ``/dev/shm`` are private tmpfs: mpirun's session folder
        and the ranks' shared-memory segments are named after its pid or its job id, the
        same in every run's namespace, so runs side by side would share them (the ranks of
        one crashed with a segmentation fault, the other's hung) and a killed run's would
        stay behind. Needs root. ``case`` may be relative to the process's working folder
        (e.g. "." in a script).
        """
        if n_procs < 2:
            raise FoamConfigError(f"n_procs = {n_procs}: an MPI run needs at least 2 ranks")
        if self.kind != "embedded":
            return [*MPIRUN, "-np", str(n_procs),
                    *self.command(app, *args), "-parallel"]
        if os.geteuid() != 0:
            raise FoamConfigError(
                "parallel runs with the embedded OpenFOAM need root (a chroot into the "
                "runtime); run serially (run.n_procs = 1) or set EHLFOAM_FOAM=native/prefix")
        root = self._root()
        allow = " ".join(f"{k}=1" for k in (
            "OMPI_ALLOW_RUN_AS_ROOT", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM",
            "PRTE_ALLOW_RUN_AS_ROOT", "PRTE_ALLOW_RUN_AS_ROOT_CONFIRM"))
        inner = shlex.join([*MPIRUN, "-np", str(n_procs), app, *args,
                            "-parallel"])
        shm = shlex.quote(str(root / "dev" / "shm"))
        script = (f"mount --bind {shlex.quote(str(case))} {shlex.quote(str(root / 'mnt'))} && "
                  f"mount -t proc proc {shlex.quote(str(root / 'proc'))} && "
                  f"mount -t tmpfs tmpfs {shlex.quote(str(root / 'tmp'))} && "
                  f"mkdir -p {shm} && mount -t tmpfs tmpfs {shm} && "
                  f"exec chroot {shlex.quote(str(root))} env -i PATH=/usr/bin:/bin HOME=/root "
                  f"WM_PROJECT_DIR=/usr/share/openfoam {allow} "
                  f"sh -c {shlex.quote('cd /mnt && exec ' + inner)}")
        return ["unshare", "--mount", "--pid", "--fork", "--kill-child=SIGKILL",
                "sh", "-c", script]

    def command_prefix(self) -> str:
        """The command as text, with ``<app>`` for the application (for display)."""
        argv = self.command("APP")
        head, app_word = argv[:-1], argv[-1][: -len("APP")] + "<app>"
        return " ".join([*(shlex.quote(a) for a in head), app_word])

    def env(self, base: Mapping[str, str] | None = None) -> dict[str, str]:
        """The environment for OpenFOAM processes: ``base`` (default
        ``os.environ``) plus ``WM_PROJECT_DIR`` for embedded and native.
        Never adds a library path."""
        env = dict(os.environ if base is None else base)
        if self.project_dir is not None:
            env["WM_PROJECT_DIR"] = str(self.project_dir)
        return env

    def describe(self) -> dict[str, str]:
        """Human-readable facts for ``ehlfoam doctor``."""
        info = {"kind": self.kind, "command": self.command_prefix()}
        if self.project_dir is not None:
            info["WM_PROJECT_DIR"] = str(self.project_dir)
        if self.kind == "embedded":
            info["root"] = str(self.root)
            stamp = self._root() / EMBEDDED_STAMP
            if stamp.is_file():
                for line in stamp.read_text().splitlines():
                    key, _, value = line.partition("=")
                    if key == "openfoam":
                        info["version"] = f"Debian openfoam {value}"
        return info

    def ensure_present(self) -> None:
        """Raise :class:`FoamRuntimeMissing` with set-up advice when the
        configured installation is clearly not there."""
        if self.kind == "embedded":
            root = self._root()
            if not (root / EMBEDDED_STAMP).is_file() or not (root / EMBEDDED_LOADER).exists():
                raise FoamRuntimeMissing(
                    f"The embedded OpenFOAM runtime (Debian 13 OpenFOAM v1912) is not "
                    f"installed at {root}. {_SETUP_HINT}")
        elif (self.kind == "native"
              and shutil.which("blockMesh", path=self.env().get("PATH")) is None):
            raise FoamRuntimeMissing(
                "EHLFOAM_FOAM=native but no OpenFOAM application (blockMesh) is on PATH. "
                + _SETUP_HINT)

    def _checked_case(self, app: str, cwd: str | os.PathLike[str]) -> Path:
        """The absolute case folder, after checking the runtime, the folder and the app."""
        self.ensure_present()
        case = Path(cwd).absolute()
        if not case.is_dir():
            raise FoamError(f"{app}: case folder {case} does not exist")
        if self.kind == "embedded" and not Path(self.app_path(app)).is_file():
            raise FoamError(f"OpenFOAM application {app!r} not found in the embedded runtime "
                            f"({self.app_path(app)} does not exist); case {case}")
        if self.kind == "native" and shutil.which(app, path=self.env().get("PATH")) is None:
            raise FoamError(f"OpenFOAM application {app!r} not found on PATH "
                            f"(EHLFOAM_FOAM=native); case {case}")
        return case

    # ----------------------------------------------------------------- start
    def popen(
        self,
        app: str,
        args: Sequence[str | os.PathLike[str]] = (),
        cwd: str | os.PathLike[str] = ".",
        log_path: str | os.PathLike[str] = "log",
        n_procs: int = 1,
        keep_fds: Sequence[int] = (),
    ) -> subprocess.Popen:
        """Start ``app args`` in the case folder ``cwd`` without waiting, stdout and stderr
        to ``log_path`` (relative to ``cwd``); on ``n_procs`` MPI ranks (decomposed case)
        when n_procs > 1. The caller waits for or stops the process.

        The process dies with the calling thread (parent-death signal: SIGKILL, or SIGTERM
        for the user's own mpirun, which then stops its ranks; an embedded parallel run's
        ranks die with its PID namespace). ``keep_fds`` are handed to it open (e.g. the
        case's run lock, which then stays held while the solver lives)."""
        case = self._checked_case(app, cwd)
        argv = self.command(app, *args) if n_procs < 2 else self.mpi_command(app, n_procs, case,
                                                                             *args)
        death = signal.SIGTERM if n_procs > 1 and self.kind != "embedded" else signal.SIGKILL
        log = case / log_path
        with open(log, "w", encoding="utf-8", errors="replace") as fh:
            try:
                return subprocess.Popen(argv, cwd=case, env=self.env(), stdout=fh,
                                        stderr=subprocess.STDOUT, start_new_session=True,
                                        pass_fds=tuple(keep_fds),
                                        preexec_fn=die_with_parent(death))
            except FileNotFoundError as exc:
                raise FoamError(f"{app}: cannot start {argv[0]!r} ({exc.strerror}); "
                                f"runtime {self.kind}; case {case}") from exc

    # ----------------------------------------------------------------- run
    def run(
        self,
        app: str,
        args: Sequence[str | os.PathLike[str]] = (),
        cwd: str | os.PathLike[str] = ".",
        log_path: str | os.PathLike[str] | None = None,
        check: bool = True,
        timeout: float | None = None,
    ) -> subprocess.CompletedProcess[str]:
        """Run ``app args`` in the case folder ``cwd``.

        stdout and stderr go together to ``log_path`` (if given) and are
        returned as ``.stdout`` of the result. With ``check`` a non-zero exit
        raises :class:`FoamError` naming the app, the case folder and the
        last lines of the log. A missing installation or application always
        raises.
        """
        case = self._checked_case(app, cwd)
        argv = self.command(app, *args)
        log = Path(log_path).absolute() if log_path is not None else None
        try:
            if log is not None:
                log.parent.mkdir(parents=True, exist_ok=True)
                with open(log, "w", encoding="utf-8", errors="replace") as fh:
                    proc = subprocess.run(argv, cwd=case, env=self.env(), stdout=fh,
                                          stderr=subprocess.STDOUT, timeout=timeout,
                                          check=False, preexec_fn=die_with_parent())
                output = log.read_text(encoding="utf-8", errors="replace")
            else:
                proc = subprocess.run(argv, cwd=case, env=self.env(), stdout=subprocess.PIPE,
                                      stderr=subprocess.STDOUT, timeout=timeout, check=False,
                                      text=True, errors="replace",
                                      preexec_fn=die_with_parent())
                output = proc.stdout or ""
        except FileNotFoundError as exc:
            raise FoamError(f"{app}: cannot start {argv[0]!r} ({exc.strerror}); "
                            f"runtime {self.kind}; case {case}") from exc
        except subprocess.TimeoutExpired as exc:
            raise FoamError(f"{app} timed out after {timeout} s in case {case}"
                            + (f" (log: {log})" if log else "")) from exc
        result = subprocess.CompletedProcess(argv, proc.returncode, stdout=output, stderr=None)
        if check and proc.returncode != 0:
            tail = "\n".join("    " + ln for ln in output.rstrip().splitlines()[-20:])
            raise FoamError(
                f"{app} failed with exit code {proc.returncode} in case {case}"
                + (f" (log: {log})" if log else "")
                + f"\n  command: {shlex.join(argv)}\n  last lines:\n{tail or '    (no output)'}")
        return result


# --------------------------------------------------------------- build check
_VELOCITY_ERROR = re.compile(
    r"Interpolated velocity error\s*=\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|[-+]?nan|[-+]?inf)",
    re.IGNORECASE)


def parse_velocity_error(log_text: str) -> float | None:
    """The last "Interpolated velocity error = X" value printed by potentialFoam."""
    matches = _VELOCITY_ERROR.findall(log_text)
    return float(matches[-1]) if matches else None


@dataclass(frozen=True)
class BuildCheck:
    """Result of the potentialFoam pitzDaily check of an OpenFOAM build.

    potentialFoam prints "Interpolated velocity error", the mismatch between
    the face fluxes and the flux of the velocity reconstructed from them
    (``fvc::reconstruct``). A correct build gives ~1.1e-4; Debian 12's
    ``openfoam 1912.200626-1+b1`` gives 1218.37, and interFoam and its
    family diverge with it on any gap whose walls are not axis-aligned.
    """

    error: float | None
    threshold: float = GOOD_BUILD_MAX_ERROR
    log: str = ""

    @classmethod
    def from_log(cls, log_text: str, threshold: float = GOOD_BUILD_MAX_ERROR) -> BuildCheck:
        return cls(error=parse_velocity_error(log_text), threshold=threshold, log=log_text)

    @property
    def ok(self) -> bool:
        return (self.error is not None and math.isfinite(self.error)
                and abs(self.error) < self.threshold)

    def summary(self) -> str:
        if self.error is None:
            return ("BROKEN: potentialFoam printed no 'Interpolated velocity error'; "
                    "cannot judge this build")
        measured = f"Interpolated velocity error = {self.error:.6g} (limit {self.threshold:g})"
        if self.ok:
            return f"OK: {measured}"
        return (f"BROKEN: {measured}. This build computes fvc::reconstruct wrongly "
                "(as Debian 12's openfoam 1912.200626-1+b1 does, error 1218.37); "
                "interFoam would diverge on curved gaps. Use the embedded Debian 13 "
                "runtime (EHLFOAM_FOAM=embedded) or another OpenFOAM.")


def _pitzdaily_source(runtime: FoamRuntime) -> Path:
    if (_PITZDAILY_TEMPLATE / "system" / "blockMeshDict").is_file():
        return _PITZDAILY_TEMPLATE
    if runtime.project_dir is not None:  # fall back to an installed tutorial
        tut = runtime.project_dir / "tutorials/basic/potentialFoam/pitzDaily"
        if (tut / "system" / "blockMeshDict").is_file():
            return tut
    raise FoamError(f"pitzDaily check case not found ({_PITZDAILY_TEMPLATE})")


def check_build(runtime: FoamRuntime, workdir: str | os.PathLike[str] | None = None,
                threshold: float = GOOD_BUILD_MAX_ERROR) -> BuildCheck:
    """Run the potentialFoam pitzDaily tutorial (blockMesh, potentialFoam
    -writePhi) with ``runtime`` and judge its "Interpolated velocity error".

    The case is copied from ``templates/checks/pitzDaily`` into ``workdir``
    (default: a temporary folder, removed afterwards). Raises
    :class:`FoamError` when an application cannot run; returns a
    :class:`BuildCheck` (see ``.ok``) otherwise. Takes about a second.
    """
    src = _pitzdaily_source(runtime)

    def _run_in(base: Path) -> BuildCheck:
        case = base / "pitzDaily"
        shutil.copytree(src, case, dirs_exist_ok=True)
        if not (case / "0").is_dir() and (case / "0.orig").is_dir():
            shutil.copytree(case / "0.orig", case / "0")
        runtime.run("blockMesh", [], cwd=case, log_path=case / "log.blockMesh")
        res = runtime.run("potentialFoam", ["-writePhi"], cwd=case,
                          log_path=case / "log.potentialFoam")
        return BuildCheck.from_log(res.stdout, threshold=threshold)

    if workdir is not None:
        base = Path(workdir)
        base.mkdir(parents=True, exist_ok=True)
        return _run_in(base)
    with tempfile.TemporaryDirectory(prefix="ehlfoam-check-") as tmp:
        return _run_in(Path(tmp))
