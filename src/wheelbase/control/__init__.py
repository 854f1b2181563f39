"""Controllers: one module per family; each controller holds gains and limits and is called as
``controller(t, pose, reference) -> command``."""

__all__: list[str] = []
