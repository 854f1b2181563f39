"""The protocol every kinematic model follows, and the shared plumbing.

A kinematic model maps its inputs (wheel speeds, steering angle and speed, ...) to a body twist
ζ = (u, v, r): forward speed [m/s], lateral speed [m/s] and yaw rate [rad/s] in the body frame
(x forward, y left). The pose rate follows from η̇ = J(θ)·ζ (document 000 §3.1). Because ζ depends
on the inputs only, never on the pose, one integrator (:mod:`wheelbase.integrate`) serves every
model, and a batch of robots is the same call with a leading axis.
"""

from __future__ import annotations

from typing import ClassVar, Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array
from wheelbase.geometry import to_world_frame

__all__ = ["KinematicModel", "ModelBase"]


@runtime_checkable
class KinematicModel(Protocol):
    """What :func:`wheelbase.simulate` and the controllers need from a model.

    Attributes
    ----------
    input_names : tuple of str
        Names of the inputs, in the order of the last axis of an ``inputs`` array.
    input_units : tuple of str
        Their SI units.
    """

    input_names: ClassVar[tuple[str, ...]]
    input_units: ClassVar[tuple[str, ...]]

    def twist(self, inputs: ArrayLike) -> np.ndarray:
        """Body twist ``(..., 3)`` = (u, v, r) for inputs of shape ``(..., k)``."""
        ...

    def derivative(self, pose: ArrayLike, inputs: ArrayLike) -> np.ndarray:
        """Pose rate η̇ = J(θ)·ζ(inputs) ``(..., 3)`` [m/s, m/s, rad/s].

        Parameters
        ----------
        pose : array_like, shape (..., 3)
            Poses (x [m], y [m], θ [rad]).
        inputs : array_like, shape (..., k)
            Model inputs in the order of ``input_names``.
        """
        ...

    def validate_inputs(self, inputs: ArrayLike) -> np.ndarray:
        """Return inputs as a float array ``(..., k)``, or raise InputError."""
        ...


class ModelBase:
    """Shared implementation of :class:`KinematicModel` for the concrete models.

    Subclasses set ``input_names``/``input_units`` and implement ``_twist(inputs)`` on a
    validated float array of shape ``(..., k)``.
    """

    input_names: ClassVar[tuple[str, ...]] = ()
    input_units: ClassVar[tuple[str, ...]] = ()

    @property
    def n_inputs(self) -> int:
        """Number of inputs k."""
        return len(self.input_names)

    def validate_inputs(self, inputs: ArrayLike) -> np.ndarray:
        """Return ``inputs`` as a finite float64 array of shape ``(..., k)``.

        Raises
        ------
        InputError
            On a wrong last axis, NaN/inf, or a value outside what the model allows.
        """
        return as_float_array(
            f"{type(self).__name__} inputs {self.input_names}", inputs, self.n_inputs
        )

    def twist(self, inputs: ArrayLike) -> np.ndarray:
        """Body twist ζ = (u, v, r) of shape ``(..., 3)`` [m/s, m/s, rad/s].

        Parameters
        ----------
        inputs : array_like, shape (..., k)
            Model inputs in the order of ``input_names``, SI units.
        """
        return self._twist(self.validate_inputs(inputs))

    def derivative(self, pose: ArrayLike, inputs: ArrayLike) -> np.ndarray:
        """Pose rate η̇ = J(θ)·ζ(inputs) of shape ``(..., 3)`` [m/s, m/s, rad/s].

        Parameters
        ----------
        pose : array_like, shape (..., 3)
            Poses (x [m], y [m], θ [rad]) in the world frame.
        inputs : array_like, shape (..., k)
            Model inputs; broadcast against ``pose``.
        """
        pose = as_float_array("pose", pose, 3)
        return to_world_frame(pose[..., 2], self.twist(inputs))

    def _twist(self, inputs: np.ndarray) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError

    @staticmethod
    def _stack_twist(u: ArrayLike, v: ArrayLike, r: ArrayLike) -> np.ndarray:
        return np.stack(np.broadcast_arrays(u, v, r), -1).astype(np.float64, copy=False)
