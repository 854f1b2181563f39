"""Sub-commands of the ``wheelbase`` CLI, one module per area.

Each module defines ``register(app: typer.Typer) -> None`` that adds its commands;
:mod:`wheelbase.cli` calls them all. Commands are thin layers over one Python call each.
"""
