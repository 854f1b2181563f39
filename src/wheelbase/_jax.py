"""JAX as an optional dependency (private): a clear error when missing, float64 on request."""

from __future__ import annotations

from typing import Any

from wheelbase.errors import ConfigError

__all__ = ["X64", "import_jax"]


def import_jax() -> tuple[Any, Any]:
    """``(jax, jax.numpy)``, or a ConfigError naming the extra to install."""
    try:
        import jax
        import jax.numpy as jnp
    except ImportError:
        raise ConfigError(
            "backend='jax' needs JAX: install the extra with pip install 'wheelbase[jax]'"
        ) from None
    return jax, jnp


class X64:
    """Enable float64 in JAX inside a block (restores the previous setting).

    JAX's precision is a process-wide setting: do not use two blocks from several threads at
    once.

    Parameters
    ----------
    jax : module
        The jax module.
    enabled : bool
        Whether to switch float64 on inside the block.
    """

    def __init__(self, jax: Any, enabled: bool) -> None:
        self.jax, self.enabled = jax, enabled

    def __enter__(self) -> None:
        self.before = bool(self.jax.config.read("jax_enable_x64"))
        self.changed = self.enabled and not self.before
        if self.changed:
            self.jax.config.update("jax_enable_x64", True)

    def __exit__(self, *exc: object) -> None:
        # Only undo what was done: a config update costs a few hundred microseconds.
        if self.changed:
            self.jax.config.update("jax_enable_x64", self.before)
