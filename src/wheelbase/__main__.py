"""``python -m wheelbase``: the command line where the ``wheelbase`` script is not on PATH
(outside an activated virtual environment, or with this interpreter's install rather than
another's)."""

from wheelbase.cli import app

__all__: list[str] = []

if __name__ == "__main__":
    app(prog_name="wheelbase")
