"""3D confirmations of a thin-film map (the batch spec's ``[confirm]`` table).

When every case of the plan has run, the regime analysis finds each thin-film line's
transition; the two points either side of it (its highest speed in state I, its lowest in
state II above it) are run again on a 3D rung (``confirm.rung``, the scene
``confirm.scene``, the overrides ``confirm.set``; the lines whose cases have the values of
``confirm.only``), each started from the thin-film case's own state. Their ids are
``confirm_`` and the 3D case's id; ``results.csv`` says which thin-film case each confirms
(``confirms``), and the regime analysis whether the two rungs agree on the state
(:func:`ehlfoam.batch.regime.confirmations`). The plan of the confirmations follows from the
finished map alone, so a batch that resumes finds the same cases and keeps those that ran.

A map of cycles (``supply.mode = "rig"``) is confirmed at the supply each cycle settled on:
the 3D case takes in, as a "layers" supply, the band of oil the tracks bring the contact's
rows after the cycle's last pass (:func:`ehlfoam.run.cycle.settled_supply`; a dry middle
where the tracks have one), started from the cycle's contact. It checks the state the
settled supply gives, not the cycle itself (a 3D cycle of passes would take days).
"""

from __future__ import annotations

from pathlib import Path

from ehlfoam.batch.folder import CASES
from ehlfoam.batch.plan import PARAM_KEYS, PlannedCase, case_id, value_of
from ehlfoam.batch.regime import analyse, row_rung, row_supply
from ehlfoam.batch.spec import BatchSpec
from ehlfoam.errors import SpecError
from ehlfoam.run.cycle import settled_supply
from ehlfoam.spec.case import CaseSpec, make_case_spec
from ehlfoam.spec.cycle import rig_layers

__all__ = ["PREFIX", "check_confirm", "confirm_plan", "confirm_spec"]

#: how the id of a confirming case starts
PREFIX = "confirm_"


def confirm_spec(batch: BatchSpec, thin_film: CaseSpec,
                 settled: dict[str, float] | None = None) -> CaseSpec:
    """The 3D case of a thin-film case's point: its contact, supply, oil, pressures and
    domain on ``confirm.rung`` in ``confirm.scene`` with ``confirm.set`` on top (the
    thin-film case's grid and run limits are the model's own and are left behind). A cycle's
    supply becomes the "layers" supply ``settled`` (dotted supply keys; none: the tracks'
    layers at the cycle's start). Raises :class:`SpecError`."""
    conf = batch.confirm
    data = thin_film.to_toml_dict()
    for key in ("rung", "scene", "mesh", "run", "name", "cycle"):
        data.pop(key, None)
    if thin_film.supply.mode == "rig":
        data["supply"] = _layers(data["supply"], settled or _start_band(thin_film))
    return make_case_spec(data, rung=conf.rung, scene=conf.scene, **conf.set)


def _start_band(spec: CaseSpec) -> dict[str, float]:
    """A cycle's tracks at its start as a "layers" supply (dotted keys)."""
    disc, ball = rig_layers(spec)
    return {"supply.disc_layer": disc, "supply.ball_layer": ball}


def _layers(supply: dict, band: dict[str, float]) -> dict:
    """A "rig" supply table as the "layers" one of ``band`` (its rig-only keys dropped)."""
    out = {k: v for k, v in supply.items()
           if k not in ("disc_oil", "ball_oil", "track_radius")}
    return {**out, "mode": "layers", **{k.split(".", 1)[1]: v for k, v in band.items()}}


def check_confirm(batch: BatchSpec, plan: list[PlannedCase]) -> None:
    """Before any work: a ``[confirm]`` table needs thin-film cases, and the 3D case of the
    first one must be a valid case spec (:class:`SpecError` naming ``confirm`` otherwise)."""
    if batch.confirm is None:
        return
    thin = [pc for pc in plan if pc.spec.scene == "thin-film" and pc.ramp is None]
    if not thin:
        raise SpecError("invalid batch spec: confirm: the batch has no thin-film sweep case "
                        "(confirm runs 3D cases either side of a thin-film map's transitions: "
                        "sweep rung = [\"thin-film-medium\"] or scene = [\"thin-film\"])")
    _spec_of(batch, thin[0])


def confirm_plan(batch: BatchSpec, plan: list[PlannedCase], rows: list[dict],
                 batch_dir: Path) -> list[PlannedCase]:
    """The confirming cases of the finished map ``rows`` (results rows), none without a
    ``[confirm]`` table: two a thin-film line with a transition."""
    if batch.confirm is None:
        return []
    by_id = {pc.id: pc for pc in plan}
    out: dict[str, PlannedCase] = {}
    for line in analyse(r for r in rows if not str(r["case_id"]).startswith(PREFIX))["lines"]:
        if not str(line["rung"]).startswith("thin-film") or not line["bracket_m_s"]:
            continue
        for u in line["bracket_m_s"]:
            row = next(r for r in rows if row_rung(r) == line["rung"]
                       and row_supply(r) == line["supply"] and _same(r, line, u))
            tf = by_id[row["case_id"]]
            if any(value_of(tf.spec, k) != v for k, v in batch.confirm.only.items()):
                continue
            settled = settled_supply(batch_dir / CASES / tf.id) \
                if tf.spec.supply.mode == "rig" else None
            spec = _spec_of(batch, tf, settled)
            cid = PREFIX + case_id(spec)
            ramp = {"start_from": str(batch_dir / CASES / tf.id), "confirms": tf.id}
            params = {k: value_of(spec, k) for k in PARAM_KEYS}
            out[cid] = PlannedCase(cid, params, ramp, spec.model_copy(update={"name": cid}))
    return list(out.values())


def _same(row: dict, line: dict, speed: float) -> bool:
    """The row is the line's point at ``speed`` (its temperature, load and speed)."""
    try:
        return (abs(float(row["contact.speed"]) - speed) <= 1e-12
                and float(row["contact.temperature"]) == float(line["contact.temperature"])
                and float(row["contact.load"]) == float(line["contact.load"]))
    except (TypeError, ValueError, KeyError):
        return False


def _spec_of(batch: BatchSpec, tf: PlannedCase,
             settled: dict[str, float] | None = None) -> CaseSpec:
    try:
        return confirm_spec(batch, tf.spec, settled)
    except SpecError as err:
        raise SpecError(f"invalid batch spec: confirm: the 3D case of {tf.id}: "
                        f"{str(err).removeprefix('invalid case spec: ')}") from None
