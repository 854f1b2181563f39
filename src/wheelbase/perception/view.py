"""What a local controller may see of its robot's perception at one step."""

from __future__ import annotations

from dataclasses import dataclass

from wheelbase._validate import finite
from wheelbase.errors import InputError
from wheelbase.perception.costmap import Costmap
from wheelbase.perception.tracking import Tracks

__all__ = ["LocalView"]


@dataclass(frozen=True, eq=False)
class LocalView:
    """A robot's perception at one step, handed to controllers that declare
    ``uses_perception = True`` as ``controller(t, measured, reference, perception=view)``.

    Parameters
    ----------
    costmap : Costmap
        The rolling window around the robot (or the whole master costmap).
    tracks : Tracks
        The tracked obstacles (tentative ones included: check ``tracks.confirmed``).
    time : float
        Time [s] of the perception (of the latest scan it holds).
    """

    costmap: Costmap
    tracks: Tracks
    time: float

    def __post_init__(self) -> None:
        if not isinstance(self.costmap, Costmap):
            raise InputError(f"costmap must be a Costmap (got {type(self.costmap).__name__})")
        if not isinstance(self.tracks, Tracks):
            raise InputError(f"tracks must be Tracks (got {type(self.tracks).__name__})")
        object.__setattr__(self, "time", finite("time", self.time, "s", InputError))
