"""The two input-as-velocity models: a body twist (u, v, r) and the unicycle (v, ω)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array
from wheelbase.models.base import ModelBase

__all__ = ["BodyTwist", "Unicycle"]


@dataclass(frozen=True)
class BodyTwist(ModelBase):
    """A planar rigid body commanded directly by its body twist (document 000 §3.1, program 1).

    Inputs are ``(u, v, r)``: forward speed [m/s], lateral speed [m/s] (positive to the left)
    and yaw rate [rad/s]; η̇ = J(ψ)·ζ. This is the kinematics of a holonomic base.
    """

    input_names: ClassVar[tuple[str, ...]] = ("u", "v", "r")
    input_units: ClassVar[tuple[str, ...]] = ("m/s", "m/s", "rad/s")

    def _twist(self, inputs: np.ndarray) -> np.ndarray:
        return inputs

    def inverse(self, twist: ArrayLike) -> np.ndarray:
        """Inputs for a body twist: the twist itself."""
        return as_float_array("twist", twist, 3)


@dataclass(frozen=True)
class Unicycle(ModelBase):
    """Unicycle: forward speed v [m/s] and yaw rate ω [rad/s] (document 002 eq. 5).

    ẋ = v cos θ, ẏ = v sin θ, θ̇ = ω.
    """

    input_names: ClassVar[tuple[str, ...]] = ("v", "omega")
    input_units: ClassVar[tuple[str, ...]] = ("m/s", "rad/s")

    def _twist(self, inputs: np.ndarray) -> np.ndarray:
        v = inputs[..., 0]
        return self._stack_twist(v, np.zeros_like(v), inputs[..., 1])

    def inverse(self, twist: ArrayLike) -> np.ndarray:
        """Inputs (v, ω) for a body twist; its lateral component is dropped."""
        twist = as_float_array("twist", twist, 3)
        return twist[..., [0, 2]].copy()
