"""Write a precalc result: ``summary.json``, ``solution.npz`` and ``precalc.png``.

Every file is written to a temporary name in the same folder and renamed into place, so a
reader never sees a half-written file.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ehlfoam._io import atomic_write, atomic_write_json, finite_or_none
from ehlfoam.contact.solver import PrecalcResult


def write_summary(result: PrecalcResult, out: Path) -> dict:
    summary = finite_or_none(result.summary())
    atomic_write_json(out / "summary.json", summary)
    return summary


def write_solution(result: PrecalcResult, out: Path) -> None:
    """x, y [m] (1-D grid axes), p [Pa] and h [m] on the grid (y rows, x columns)."""
    c, mg = result.contact, result.mg
    arrays = dict(x=mg.x * c.a, y=mg.y * c.a, p=mg.P * c.p_hertz, h=mg.H * c.film_scale,
                  a_m=c.a, radius_m=c.radius, p_hertz_Pa=c.p_hertz, h0_m=mg.H0 * c.film_scale)
    atomic_write(out / "solution.npz", lambda fh: np.savez_compressed(fh, **arrays))


def write_plot(result: PrecalcResult, out: Path) -> None:
    """Pressure and film on the centrelines and as maps (units a, GPa, nm)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    c, mg = result.contact, result.mg
    j, i = result.centre_index()
    p_gpa = mg.P * c.p_hertz / 1e9
    h_nm = mg.H * c.film_scale * 1e9
    fig, ax = plt.subplots(2, 2, figsize=(11, 8))
    for col, (coord, p_line, h_line, lab) in enumerate(
        [(mg.x, p_gpa[j], h_nm[j], "x / a  (y = 0)"), (mg.y, p_gpa[:, i], h_nm[:, i], "y / a  (x = 0)")]
    ):
        a1 = ax[0, col]
        a1.plot(coord, p_line, "C0")
        a1.set_xlabel(lab)
        a1.set_ylabel("p [GPa]", color="C0")
        a2 = a1.twinx()
        a2.plot(coord, h_line, "C1")
        a2.set_ylabel("h [nm]", color="C1")
        top = 5 * result.H_central * c.film_scale * 1e9
        if np.isfinite(top) and top > 0:  # a failed solution still gets its plot
            a2.set_ylim(0, top)
    ext = [mg.x[0], mg.x[-1], mg.y[0], mg.y[-1]]
    im = ax[1, 0].imshow(p_gpa, origin="lower", extent=ext, cmap="viridis")
    fig.colorbar(im, ax=ax[1, 0], label="p [GPa]")
    hc = result.H_central * c.film_scale * 1e9
    im = ax[1, 1].imshow(h_nm, origin="lower", extent=ext, cmap="magma", vmin=0, vmax=3 * hc)
    fig.colorbar(im, ax=ax[1, 1], label="h [nm]")
    theta = np.linspace(0, 2 * np.pi, 200)
    for a_ in ax[1]:
        a_.plot(np.cos(theta), np.sin(theta), "w--", lw=0.8)
        a_.set_xlabel("x / a")
        a_.set_ylabel("y / a")
    s = result.spec
    fig.suptitle(
        f"F = {s.load:g} N, u = {s.speed * 1e3:g} mm/s, T = {s.temperature:g} C: M = {c.M:.0f}, "
        f"L = {c.L:.2f}, hc = {hc:.2f} nm, hmin = {mg.H.min() * c.film_scale * 1e9:.2f} nm, "
        f"grid {result.domain.nx}x{result.domain.ny}, converged = {result.converged}")
    fig.tight_layout()
    atomic_write(out / "precalc.png", lambda fh: fig.savefig(fh, format="png", dpi=110))
    plt.close(fig)


def write_all(result: PrecalcResult, out: str | Path) -> dict:
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    write_solution(result, out)
    write_plot(result, out)
    return write_summary(result, out)
