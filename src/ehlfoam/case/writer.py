"""Write a complete OpenFOAM case from a :class:`~ehlfoam.spec.case.CaseSpec`.

    spec -> gap (ehlfoam.gap, cached) -> mesh (ehlfoam.mesh: gmsh base, extruded on h) -> case

The case is the template folder ``templates/<scene>/`` copied and edited with foamlib (values
marked "set by the generator" in the templates; :mod:`.fields`, :mod:`.dictionaries`), the
mesh written directly as a polyMesh, and ``ehlfoam/`` holding what the monitor and the
metrics need (the spec, the geometry (:mod:`.geometry`), the mesh's 2D structure) and the
marker ``ehlfoam/case.json`` that makes the folder the tool's own (:mod:`.ownership`). The case
also runs by hand: ``DIR/Allrun``, ``DIR/Allclean``.

The case is built in a temporary sibling folder and renamed into place only when complete
(a start from another state is written into it first, see ``prepare``): a failure leaves
nothing behind, and an earlier case replaced with ``overwrite`` stays whole until then.
``overwrite`` replaces only an empty folder or a case the tool wrote, never one being run
(:func:`.ownership.check_replaceable`).
"""

from __future__ import annotations

import json
import math
import os
import re
import shlex
import shutil
import tempfile
import time
from dataclasses import asdict
from collections.abc import Callable
from pathlib import Path

import numpy as np

from ehlfoam._io import atomic_write_json, atomic_write_text, link_tree
from ehlfoam.case.bounds import check_work
from ehlfoam.case.dictionaries import edit_physics_dicts, edit_run_control, release_geometry
from ehlfoam.case.fields import edit_fields, with_supply_patch
from ehlfoam.case.geometry import META, CaseGeometry
from ehlfoam.case.ownership import (CaseBeingRun, CaseBusy, CaseExists, check_replaceable,
                                    hold_run_lock, write_marker)
from ehlfoam.case.thin_film import thin_film_case
from ehlfoam.case.timestep import capillary_time_step, write_interval
from ehlfoam.foam.runtime import FoamRuntime
from ehlfoam.gap.source import load_gap
from ehlfoam.mesh import (BaseMesh, MeshParams, PolyMesh, build_base_mesh, extrude, gap_mismatch,
                          size_function, smallest_cell_size, wall_steps, write_polymesh)
from ehlfoam.mesh.sizing import mesh_params
from ehlfoam.spec.case import CaseSpec

TEMPLATES = Path(__file__).resolve().parent / "templates"
#: In a case being built (a temporary folder beside its place): the builder's pid.
BUILDER = ".ehlfoam-build"

__all__ = ["CaseBeingRun", "CaseExists", "case_mesh", "extrude_level", "write_case"]


def extrude_level(spec: CaseSpec, base: BaseMesh, gap) -> PolyMesh:
    """``base`` extruded across ``gap(x, y)`` [m] in the spec's layers: the level's count and
    wall grading, or one wall cell height everywhere (``mesh.wall_cell``)."""
    level = spec.mesh.level()
    return extrude(base, gap, level["n_layers"], level["wall_grading"] or 1.0,
                   spec.mesh.columns, wall_cell=level["wall_cell"])


def _edit_dicts(spec: CaseSpec, case: Path, geom: CaseGeometry) -> None:
    edit_physics_dicts(spec, case)
    edit_run_control(spec, case, geom.end_time, geom.write_interval, geom.max_delta_t)


#: A marker of the hand-run scripts, ``@NAME@``, that :func:`_write_scripts` fills
_MARKER = re.compile(r"@([A-Z_]+)@")


def script_values(runtime: FoamRuntime, n_procs: int, solver: str) -> dict[str, str]:
    """What the Allrun's markers get, each already shell-quoted: the launch words and the
    parallel command as quoted words (:func:`shlex.join`), every other value one quoted word
    (:func:`shlex.quote`), so that no ``$(...)``, backquote, ``;``, space or quote in a path
    (``EHLFOAM_CACHE``, ``EHLFOAM_FOAM_PREFIX``, ``WM_PROJECT_DIR``) is expanded by the
    shell that runs the script."""
    argv = runtime.command("APP")
    app_path = Path(argv[-1])
    return {"FOAM_LAUNCH": shlex.join(argv[:-1]),
            "FOAM_BIN": shlex.quote(str(app_path.parent) if app_path.is_absolute() else ""),
            "WM_PROJECT_DIR": shlex.quote(runtime.env({}).get("WM_PROJECT_DIR", "")),
            "NPROCS": shlex.quote(str(int(n_procs))),
            "SOLVER": shlex.quote(solver),
            "PARALLEL_SOLVER": shlex.join(runtime.mpi_command(solver, n_procs, "."))
            if n_procs > 1 else "false"}  # the serial branch runs instead


def _write_scripts(case: Path, runtime: FoamRuntime, n_procs: int, solver: str) -> None:
    """Fill the runtime into the hand-runnable Allrun (launch words, application folder), in
    one pass: a value is never searched for markers again."""
    values = script_values(runtime, n_procs, solver)
    text = (case / "Allrun").read_text()
    (case / "Allrun").write_text(_MARKER.sub(lambda m: values[m.group(1)], text))


def case_mesh(spec: CaseSpec, gap) -> tuple[MeshParams, BaseMesh, PolyMesh, np.ndarray]:
    """The mesh :func:`write_case` writes for ``spec`` on the gap h(x, y) [m]: its parameters,
    the 2D base mesh, the extruded mesh with its supply patch, and the supply faces' oil
    fractions."""
    params = mesh_params(spec)
    # the mesher's own guard, at the spec's cap (check_work refuses the spec first, by the
    # same estimate, naming mesh.max_cells)
    base = build_base_mesh(params, size_function(spec),
                           max_quads=math.ceil(spec.mesh.max_cells / params.n_layers))
    mesh, supply = with_supply_patch(spec, extrude_level(spec, base, gap))
    return params, base, mesh, supply


def write_case(spec: CaseSpec, out: str | os.PathLike, runtime: FoamRuntime | None = None,
               overwrite: bool = False,
               prepare: Callable[[Path], object] | None = None) -> CaseGeometry:
    """Build the case of ``spec`` in ``out`` (atomically: built in a temporary sibling folder
    and renamed into place). ``overwrite``: ``out`` may be an earlier case the tool wrote
    (not one being run); anything else that is not empty is refused with
    :class:`CaseExists` before any work. A spec whose case would exceed ``mesh.max_cells``
    or ``run.max_steps`` is refused next (:func:`ehlfoam.case.bounds.check_work`, a
    SpecError), before the EHL precalc. ``prepare`` is called with the complete temporary
    case folder before it is renamed into place (a start from another state); if it raises,
    nothing is left and an earlier case stays as it was. Returns the case's
    :class:`CaseGeometry`."""
    out = Path(out).absolute()
    if spec.mesh.follow is not None:
        raise ValueError("mesh.follow needs the state the case starts from, whose meniscus "
                         "the mesh follows: ehlfoam case SPEC --out DIR --start-from SOURCE "
                         "(ehlfoam.seed.follow.write_started_case)")
    check_replaceable(out, overwrite)
    check_work(spec)   # the mesh and the time steps within their caps, before the precalc
    if spec.scene == "thin-film":   # the gap-averaged model's case: no OpenFOAM (issue 74)
        geom, fill = thin_film_case(spec)
        _build(out, overwrite, fill, prepare)
        return geom
    runtime = runtime or FoamRuntime.from_environment()
    gap, precalc = load_gap(spec.contact)
    a = spec.a
    params, base, mesh, supply = case_mesh(spec, gap)
    steps = float(np.median(wall_steps(base, mesh)))
    dx = smallest_cell_size(spec)
    dt = capillary_time_step(spec, dx)
    interval = write_interval(spec)
    summary = json.loads((precalc / "summary.json").read_text())
    hc = float(summary["hc_m"])
    geom = CaseGeometry(
        a=a, radius=spec.contact.radius, speed=spec.speed, x_min=params.x_min,
        x_max=params.x_max, y_max=params.y_max, island_radius=params.island_radius,
        symmetric=params.symmetric, n_layers=params.n_layers, cells=len(mesh.cell_volumes),
        transit_time=spec.transit_time, end_time=spec.end_time,
        write_interval=interval,
        max_delta_t=min(dt, interval),
        capillary_limit=spec.run.capillary_limit, min_cell_size=dx,
        island_gap=float(gap(np.array([params.island_radius]), np.array([0.0]))[0]),
        hc=hc, contact_flow=spec.speed * hc * 2.0 * a,
        gap_mismatch=gap_mismatch(mesh, gap),
        oil_viscosity=spec.oil_viscosity, oil_density=spec.oil_density,
        solver=spec.solver, ambient_pressure=spec.physics.ambient_pressure,
        **release_geometry(spec), ball_wall_steps=steps,
        open_inflow_oil=1.0 if spec.fills_domain else 0.0)


    def fill(tmp: Path) -> None:
        shutil.copytree(TEMPLATES / _template_for(spec), tmp, dirs_exist_ok=True)
        write_polymesh(mesh, tmp)
        edit_fields(spec, tmp, mesh, supply, gap, geom)
        _edit_dicts(spec, tmp, geom)
        _write_scripts(tmp, runtime, spec.run.n_procs, spec.solver)
        meta = tmp / META
        meta.mkdir()
        atomic_write_text(meta / "spec.json", spec.model_dump_json(indent=2) + "\n")
        atomic_write_json(meta / "geometry.json", asdict(geom))
        _save_structure(meta / "mesh.npz", mesh)
        link_tree(precalc, tmp / "precalc")

    _build(out, overwrite, fill, prepare)
    return geom


def _build(out: Path, overwrite: bool, fill: Callable[[Path], None],
           prepare: Callable[[Path], object] | None) -> None:
    """Build a case in a temporary sibling folder of ``out`` (``fill`` writes its files),
    mark it the tool's own, let ``prepare`` add its start, and swap it into place; on any
    failure nothing is left and an earlier case stays as it was."""
    out.parent.mkdir(parents=True, exist_ok=True)
    _recover(out)
    tmp = Path(tempfile.mkdtemp(dir=out.parent, prefix=f".{out.name}."))
    (tmp / BUILDER).write_text(f"{os.getpid()}\n")
    try:
        fill(tmp)
        write_marker(tmp)
        if prepare is not None:
            prepare(tmp)
        (tmp / BUILDER).unlink()
        _swap_into_place(tmp, out, overwrite)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def _alive(pid_file: Path) -> bool:
    """The process named in ``pid_file`` (a build's) still runs."""
    try:
        os.kill(int(pid_file.read_text().split()[0]), 0)
    except (OSError, ValueError, IndexError):
        return False
    return True


def _recover(out: Path) -> None:
    """What a write of ``out`` killed before its end left beside it: an earlier case moved
    aside (``.NAME.old.*/case``) goes back to ``out`` if ``out`` is missing, else it is
    removed; a temporary build folder (``.NAME.*``) whose builder died is removed."""
    for side in sorted(out.parent.glob(f".{out.name}.*")):
        if not side.is_dir():
            continue
        if side.name.startswith(f".{out.name}.old."):
            if time.time() - side.stat().st_mtime < 60.0:   # maybe another write's, now
                continue
            if (side / "case").is_dir() and not out.exists():
                os.replace(side / "case", out)
            shutil.rmtree(side, ignore_errors=True)
        elif (side / BUILDER).is_file() and not _alive(side / BUILDER):
            shutil.rmtree(side, ignore_errors=True)


def _swap_into_place(tmp: Path, out: Path, overwrite: bool) -> None:
    """Rename the built case ``tmp`` to ``out``. An earlier case there is checked again (it
    may have changed during the build), moved aside under its run lock (so that no run can
    start on it meanwhile) and removed only once the new case is in place."""
    check_replaceable(out, overwrite)
    if not out.exists() or not any(out.iterdir()):
        os.replace(tmp, out)      # a new folder, or over an empty one
        return
    old = Path(tempfile.mkdtemp(dir=out.parent, prefix=f".{out.name}.old."))
    try:
        with hold_run_lock(out):
            os.replace(out, old / "case")
            os.replace(tmp, out)
    except CaseBusy as err:
        raise CaseBeingRun(f"--out {out} --overwrite: {err}") from None
    finally:
        shutil.rmtree(old, ignore_errors=True)


def _template_for(spec: CaseSpec) -> str:
    return {"interface": "interface", "single-phase": "interface",
            "cavitating": "cavitating", "gas-release": "interface"}[spec.scene]


def _save_structure(path: Path, mesh: PolyMesh) -> None:
    """What the monitor needs to read fields without parsing the polyMesh: per cell its
    centre, volume, 2D base cell and layer; the boundary patches' face ranges."""
    names = np.array([p.name for p in mesh.patches])
    starts = np.array([p.start for p in mesh.patches])
    sizes = np.array([p.size for p in mesh.patches])
    n_internal = len(mesh.neighbour)
    with open(path, "wb") as fh:
        np.savez_compressed(fh, cell_centres=mesh.cell_centres, cell_volumes=mesh.cell_volumes,
                            base_cell=mesh.base_cell, layer=mesh.layer, patch_names=names,
                            patch_starts=starts - n_internal, patch_sizes=sizes,
                            face_centres_boundary=mesh.face_centres[n_internal:])
