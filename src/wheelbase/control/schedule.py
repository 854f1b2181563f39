"""A controller whose model of the robot changes at known times: a payload it knows it took.

:class:`ModelSchedule` wraps a controller that has a ``model`` attribute (a
:class:`~wheelbase.dynamics.DiffDriveDynamics`: the computed-torque laws, the twist torque
loop) and sets it, before each call, to the model in force at that time. A robot that picks up
a box at a goal knows it did; one that does not is modelled by not scheduling the change (the
scenario key ``controller.model_payload``).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, ClassVar

from wheelbase.control.base import WrappedLaw
from wheelbase.dynamics import DiffDriveDynamics
from wheelbase.errors import ConfigError

__all__ = ["ModelSchedule"]


class ModelSchedule(WrappedLaw):
    """Set the wrapped controller's ``model`` from a timetable before each call.

    Parameters
    ----------
    law : object
        A controller with a settable ``model`` attribute.
    changes : sequence of (float, DiffDriveDynamics)
        From which time [s] on each model holds, increasing; before the first the law's own
        model holds.
    """

    command_names: ClassVar[tuple[str, ...]] = ("tau_left", "tau_right")

    def __init__(self, law: Any, changes: Sequence[tuple[float, DiffDriveDynamics]]) -> None:
        if not hasattr(law, "model") or not callable(law):
            raise ConfigError("a model schedule needs a controller with a model")
        times = [float(time) for time, _ in changes]
        if times != sorted(times) or not all(
            isinstance(model, DiffDriveDynamics) for _, model in changes
        ):
            raise ConfigError("the model changes must be (time, DiffDriveDynamics), increasing")
        self.law = law
        self.first = law.model
        self.changes = tuple((float(t), model) for t, model in changes)
        self.command_names = tuple(getattr(law, "command_names", self.command_names))

    def model_at(self, t: float) -> DiffDriveDynamics:
        """The model in force at ``t`` [s].

        Parameters
        ----------
        t : float
            Time [s].
        """
        model = self.first
        for start, later in self.changes:
            if t >= start - 1e-9:
                model = later
        return model

    def reset(self) -> None:
        """Back to the first model; reset the law."""
        self.law.model = self.first
        super().reset()

    @property
    def model(self) -> DiffDriveDynamics:
        """The model in force at the last call."""
        return self.law.model

    def __call__(self, t: float, *args: Any, **kwargs: Any) -> Any:
        """The law's command at ``t`` with the model in force then.

        Parameters
        ----------
        t : float
            Time [s].
        *args, **kwargs
            Passed to the law.
        """
        self.law.model = self.model_at(t)
        return self.law(t, *args, **kwargs)
