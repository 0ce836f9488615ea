"""What a 3D case leaves behind the contact: the oil through its outlet as lateral profiles.

The thin-film model adds up what leaves its outlet row by row
(:attr:`~ehlfoam.thinfilm.march.Marcher.oil_out_rows`); a 3D case's outlet is a patch of
faces, each with the oil flux through it at a written time (``alphaPhi0.oil``, or ``phi``
times the face's oil fraction where the solver does not write it, as the monitor reads them,
:func:`ehlfoam.run.fields.sample`). Binned by the faces' lateral position into rows of a
given width, the flux leaving through each row, carried away by the walls at the rolling
speed u, is the layer (both walls together) the contact lays on the tracks there:
layer = flux / (u row). Summed over the rows it is the case's outlet outflow. SI units;
rows from y = 0 outward (a full mesh folded onto y >= 0).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ehlfoam._io import atomic_write_text
from ehlfoam.case.geometry import META, load_geometry, load_spec_of
from ehlfoam.foam.fieldfile import IncompleteField, field_file
from ehlfoam.run.fields import Structure, time_folders, uniform_or_list

__all__ = ["OUTFLOW_FILE", "OUTFLOW_ROW", "OUTLET", "outlet_layers", "write_outflow"]

#: the patch the oil leaves the contact through
OUTLET = "outlet"
#: in the case folder: the layers the run's outflow lays on the tracks, row by row
OUTFLOW_FILE = "outflow.csv"
#: its rows' width [a]
OUTFLOW_ROW = 0.1


def outlet_layers(case: str | Path, row: float, rows: int,
                  time_folder: Path | None = None) -> np.ndarray:
    """The layer [m] (both walls together) the oil leaving the 3D ``case``'s outlet lays on
    each of ``rows`` rows of width ``row`` [m] from y = 0 (the faces beyond the last row in
    it), at ``time_folder`` (default: the last written time whose flux is written whole: a
    solver killed while it wrote leaves a folder cut short); the oil that flows back in
    through the outlet is taken from its row. ValueError without an outlet or a written
    time."""
    case = Path(case)
    geom, spec = load_geometry(case), load_spec_of(case)
    structure = Structure.load(case)
    if OUTLET not in structure.patches:
        raise ValueError(f"{case} has no {OUTLET!r} patch")
    start, size = structure.patches[OUTLET]
    y = np.abs(np.load(case / META / "mesh.npz")["face_centres_boundary"][start:start + size, 1])
    flux = (_outlet_oil_flux(Path(time_folder), size) if time_folder is not None
            else _last_whole_flux(case, size))
    band = np.minimum((y / row).astype(int), rows - 1)
    per_row = np.bincount(band, weights=flux, minlength=rows)
    # a full mesh folds both sides of the track onto each row: half of it is the row's
    return per_row / (spec.speed * row * (1.0 if geom.symmetric else 2.0))


def _last_whole_flux(case: Path, size: int) -> np.ndarray:
    """The outlet's oil flux at the last written time whose files are whole (a write cut
    short, or missing a file, is passed over). ValueError without one after the start."""
    for t, folder in reversed(time_folders(case)):
        if t <= 0:
            break
        try:
            return _outlet_oil_flux(folder, size)
        except (IncompleteField, FileNotFoundError):   # cut short, or not written yet
            continue
    raise ValueError(f"{case} has no written time after the start")


def _outlet_oil_flux(folder: Path, size: int) -> np.ndarray:
    """The oil flux [m3/s] out through each outlet face at ``folder``."""
    exact = (folder / "alphaPhi0.oil").exists()
    flux = uniform_or_list(field_file(folder / ("alphaPhi0.oil" if exact else "phi"))
                           .boundary_field[OUTLET]["value"], size)
    if not exact:
        alpha = uniform_or_list(
            field_file(folder / "alpha.oil").boundary_field[OUTLET]["value"], size)
        flux = flux * np.clip(alpha, 0.0, 1.0)
    return flux


def write_outflow(case: str | Path, disc_share: float = 0.5) -> Path:
    """``outflow.csv`` in the 3D ``case``: the layers [m] its outlet's oil lays on the disc
    (``disc_share`` of it; 1/2 in pure rolling) and on the ball, on rows of
    :data:`OUTFLOW_ROW` a from y = 0 to the domain's side, at the last written time (the
    profiles a cycle's tracks take, :mod:`ehlfoam.tracks`), written atomically. ValueError
    as :func:`outlet_layers`."""
    case = Path(case)
    spec, geom = load_spec_of(case), load_geometry(case)
    row = OUTFLOW_ROW * geom.a
    layers = outlet_layers(case, row, max(1, int(np.ceil(spec.domain.side / OUTFLOW_ROW))))
    lines = ["y_m,disc_layer_m,ball_layer_m"] + [
        f"{(j + 0.5) * row:.6g},{disc_share * h:.6g},{(1.0 - disc_share) * h:.6g}"
        for j, h in enumerate(layers)]
    atomic_write_text(case / OUTFLOW_FILE, "\n".join(lines) + "\n")
    return case / OUTFLOW_FILE