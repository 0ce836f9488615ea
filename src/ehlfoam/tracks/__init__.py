"""The oil on the rig's tracks: the layers the disc and the ball carry across their tracks,
their capillary reflow over a revolution (:mod:`.reflow`) and what a pass of the contact takes
from them and lays back (:mod:`.rig`): the supply as an outcome of the oil on the rig, a cycle
of passes (:mod:`ehlfoam.run.cycle`)."""

from ehlfoam.tracks.reflow import ReflowResult, levelling_rate, levelling_time, reflow
from ehlfoam.tracks.rig import Rig, Tracks, outlet_layers

__all__ = ["ReflowResult", "Rig", "Tracks", "levelling_rate", "levelling_time",
           "outlet_layers", "reflow"]
