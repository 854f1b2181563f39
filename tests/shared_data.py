"""Where the tests find the real data sets (MRCLAM odometry, Moving AI maps, the turtlebot3 map).

They are not in the repository: ``$WHEELBASE_DATA`` when set, else ``../shared/data`` beside the
clone. Tests that need a file skip with the reason when it is absent (a bare clone runs the
rest); the README says where to get the files.
"""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["DATA", "absent"]

DATA = Path(
    os.environ.get("WHEELBASE_DATA") or Path(__file__).resolve().parents[2] / "shared" / "data"
)


def absent(path: Path) -> str:
    """The skip reason for a missing data file."""
    return f"{path} absent (set WHEELBASE_DATA; see the README, 'Tests and real data')"
