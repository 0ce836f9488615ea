"""The 3D mesh as OpenFOAM holds it (:class:`PolyMesh`), and its ``constant/polyMesh`` files.

:func:`write_polymesh` writes the OpenFOAM ``constant/polyMesh`` files (ASCII) directly with
numpy: no OpenFOAM utility needed.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np


@dataclass(frozen=True)
class Patch:
    """A boundary patch: faces ``start .. start + size - 1``."""

    name: str
    type: str
    start: int
    size: int


@dataclass
class PolyMesh:
    """A 3D OpenFOAM-style mesh (metres) of hexahedra.

    ``faces`` (F, 4) point ids, normal (right-hand rule) from owner to
    neighbour, pointing out of the domain on boundary faces; internal faces
    first in upper-triangular order. ``face_centres``/``face_areas``
    (F, 3) and ``cell_centres`` (C, 3)/``cell_volumes`` (C,) are computed as
    OpenFOAM does (m, m^2, m^3). ``base_cell`` is the 2D quad of each cell,
    ``layer`` its layer (0 at the disc); ``spans`` (C, 2) the bottom and top of each
    cell across its column as fractions of the gap (0 on the disc, 1 on the ball: the mean
    of its nodes' levels, :func:`extrude`).
    """

    points: np.ndarray
    faces: np.ndarray
    owner: np.ndarray
    neighbour: np.ndarray
    patches: list[Patch]
    cell_centres: np.ndarray
    cell_volumes: np.ndarray
    base_cell: np.ndarray
    layer: np.ndarray
    face_centres: np.ndarray
    face_areas: np.ndarray
    spans: np.ndarray

    @property
    def n_cells(self) -> int:
        return len(self.cell_volumes)

    @property
    def n_internal_faces(self) -> int:
        return len(self.neighbour)

    @property
    def _points_per_node(self) -> int:
        """n_layers + 1: the levels of each base node's column (:func:`extrude`'s order)."""
        return int(self.layer.max()) + 2

    def base_node(self, point_ids: np.ndarray) -> np.ndarray:
        """The 2D base-mesh node of each point id: point ``p`` is a level of node
        ``p // (n_layers + 1)`` (:func:`extrude`'s order), whether or not its column
        leans."""
        return np.asarray(point_ids) // self._points_per_node

    def top_point(self, nodes: np.ndarray) -> np.ndarray:
        """The point id of the top of each 2D base-mesh node's column, on the ball (the
        inverse of :meth:`base_node` at the last level)."""
        return (np.asarray(nodes) + 1) * self._points_per_node - 1

    def patch(self, name: str) -> Patch:
        """The patch called ``name`` (KeyError if absent)."""
        for p in self.patches:
            if p.name == name:
                return p
        raise KeyError(f"no patch {name!r}; patches: {[p.name for p in self.patches]}")

    def patch_slice(self, name: str) -> slice:
        p = self.patch(name)
        return slice(p.start, p.start + p.size)


def split_patch(mesh: PolyMesh, name: str, select: np.ndarray, new_name: str,
                new_type: str = "patch") -> PolyMesh:
    """A copy of ``mesh`` in which the faces of patch ``name`` where ``select`` (bool, one per
    face of the patch) form a new patch ``new_name`` placed right after it. Faces are only
    reordered within the old patch's range, so the rest of the mesh is unchanged."""
    sl = mesh.patch_slice(name)
    select = np.asarray(select, dtype=bool)
    if select.shape != (sl.stop - sl.start,):
        raise ValueError(f"select must have one entry per face of {name!r} "
                         f"({sl.stop - sl.start}), got shape {select.shape}")
    if any(p.name == new_name for p in mesh.patches):
        raise ValueError(f"patch {new_name!r} exists already")
    order = np.r_[np.flatnonzero(~select), np.flatnonzero(select)] + sl.start
    perm = np.arange(len(mesh.faces))
    perm[sl] = order
    patches = []
    for p in mesh.patches:
        if p.name != name:
            patches.append(p)
            continue
        kept = int((~select).sum())
        if kept:
            patches.append(Patch(p.name, p.type, p.start, kept))
        if select.any():
            patches.append(Patch(new_name, new_type, p.start + kept, int(select.sum())))
    return PolyMesh(points=mesh.points, faces=mesh.faces[perm], owner=mesh.owner[perm],
                    neighbour=mesh.neighbour, patches=patches, cell_centres=mesh.cell_centres,
                    cell_volumes=mesh.cell_volumes, base_cell=mesh.base_cell, layer=mesh.layer,
                    face_centres=mesh.face_centres[perm], face_areas=mesh.face_areas[perm],
                    spans=mesh.spans)


_BANNER = """\
/*--------------------------------*- C++ -*----------------------------------*\\
| ehlfoam: thin-gap mesh (ehlfoam.mesh.polymesh)                              |
\\*---------------------------------------------------------------------------*/
"""
#: Rows formatted per chunk when writing large lists.
_CHUNK = 65536


def _header(cls: str, obj: str, note: str | None = None) -> str:
    lines = ["FoamFile", "{", "    version     2.0;", "    format      ascii;",
             f"    class       {cls};"]
    if note:
        lines.append(f'    note        "{note}";')
    lines += ['    location    "constant/polyMesh";', f"    object      {obj};", "}"]
    return _BANNER + "\n".join(lines) + "\n// " + "* " * 37 + "//\n\n"


def _write_atomic(path: Path, chunks: Iterator[str]) -> None:
    """Write ``chunks`` to a temporary file next to ``path``, then rename it
    into place (readers never see a partial file)."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.{os.urandom(4).hex()}.tmp")
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
    try:
        with os.fdopen(fd, "w", encoding="ascii", newline="\n") as fh:
            for chunk in chunks:
                fh.write(chunk)
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def _list_chunks(header: str, rows: np.ndarray, row_format: str) -> Iterator[str]:
    """An OpenFOAM list: header, count, ``(``, one formatted row per line, ``)``."""
    yield header + f"{len(rows)}\n(\n"
    for i in range(0, len(rows), _CHUNK):
        block = rows[i:i + _CHUNK]
        yield (row_format * len(block)) % tuple(block.reshape(-1).tolist())
    yield ")\n\n// " + "*" * 73 + " //\n"


def _boundary_text(patches: list[Patch]) -> str:
    body = [f"{len(patches)}", "("]
    for p in patches:
        body += [f"    {p.name}", "    {", f"        type            {p.type};"]
        if p.type in ("wall", "symmetryPlane"):
            body.append(f"        inGroups        List<word> 1({p.type});")
        body += [f"        nFaces          {p.size};", f"        startFace       {p.start};",
                 "    }"]
    body += [")", "", "// " + "*" * 73 + " //", ""]
    return _header("polyBoundaryMesh", "boundary") + "\n".join(body)


#: Files in constant/polyMesh that describe an earlier mesh and would clash.
_STALE = ("points.gz", "faces.gz", "owner.gz", "neighbour.gz", "boundary.gz",
          "cellZones", "faceZones", "pointZones", "cellZones.gz", "faceZones.gz",
          "pointZones.gz")


def write_polymesh(mesh: PolyMesh, case_dir: str | os.PathLike[str]) -> None:
    """Write ``case_dir/constant/polyMesh/{points,faces,owner,neighbour,boundary}``
    (ASCII; points with 12 significant digits, m). Each file is written to a
    temporary file and renamed into place; compressed copies and zone files
    left by an earlier mesh are removed."""
    poly = Path(case_dir) / "constant" / "polyMesh"
    poly.mkdir(parents=True, exist_ok=True)
    n_faces, n_int, n_cells = len(mesh.faces), len(mesh.neighbour), mesh.n_cells
    if len(mesh.owner) != n_faces or sum(p.size for p in mesh.patches) != n_faces - n_int:
        raise ValueError(f"inconsistent mesh: {n_faces} faces, {len(mesh.owner)} owners, "
                         f"{n_int} internal faces, {sum(p.size for p in mesh.patches)} "
                         f"patch faces")
    note = f"nPoints:{len(mesh.points)}  nCells:{n_cells}  nFaces:{n_faces}  nInternalFaces:{n_int}"
    for name in _STALE:
        (poly / name).unlink(missing_ok=True)
    _write_atomic(poly / "points", _list_chunks(
        _header("vectorField", "points"), np.asarray(mesh.points, float),
        "(%.12g %.12g %.12g)\n"))
    _write_atomic(poly / "faces", _list_chunks(
        _header("faceList", "faces"), np.asarray(mesh.faces, np.int64), "4(%d %d %d %d)\n"))
    _write_atomic(poly / "owner", _list_chunks(
        _header("labelList", "owner", note), np.asarray(mesh.owner, np.int64)[:, None], "%d\n"))
    _write_atomic(poly / "neighbour", _list_chunks(
        _header("labelList", "neighbour", note), np.asarray(mesh.neighbour, np.int64)[:, None],
        "%d\n"))
    _write_atomic(poly / "boundary", iter([_boundary_text(mesh.patches)]))
