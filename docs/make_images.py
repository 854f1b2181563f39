"""Draw the figure of the home page and of every task page from the command the page shows.

Run ``python docs/make_images.py [--only NAME ...]`` from the repository (``--data DIR``: the real
data, default ``../shared/data``, with ``mrclam/`` and ``carmen/``). Each figure comes from running
that command through ``python -m wheelbase`` in a scratch folder; the PNG it writes is shrunk to at
most ``MAX_WIDTH`` pixels and 64 colours and saved as ``docs/images/page_NAME.png`` (tens of kB, so
the repository stays small). Prints JSON: each file with its size and the command that drew it.
The navigate page's animations (``docs/images/navigate_NAME.gif``, ``--only navigate``) are the
``animation.gif`` of ``wheelbase run NAME`` for each bundled obstacles scenario, shrunk the
smaller (:func:`shrink_gif`). No figure in the documentation is
pasted by hand; the gymnasium page's learning curve is
``examples/gym_ppo.py``'s (it trains for minutes), the terrain page's come from its own scripts.
"""

from __future__ import annotations

import argparse
import csv
import json
import re
import subprocess
import sys
import tempfile
from pathlib import Path

DOCS = Path(__file__).resolve().parent
IMAGES = DOCS / "images"
MAX_WIDTH = 760
"""Widest figure [pixels]: the width of the theme's text column."""
GIF_WIDTH = 440
"""Widest animation of the navigate page [pixels] (the run's own GIF width)."""
ANIMATIONS = ("unexpected_boxes", "crowd_crossing", "doorway_blocked", "corridor_swap")
"""The bundled scenarios animated on the navigate page."""

SIMULATE = ["simulate", "--model", "diffdrive", "--left", "0.8", "--right", "0.6", "--t-end",
            "100", "--method", "euler", "--pose0", "0,0,90", "--no-gif"]  # fmt: skip
PAGES: dict[str, tuple[list[str], str]] = {
    # page: (arguments of `wheelbase`, the file of the output folder to show)
    "index": (["demo", "--no-gif"], "map.png"),
    "simulate": (SIMULATE, "path.png"),
    "plan": (["plan", "--case", "parallel_115_in"], "path.png"),
    "control": (["control", "--law", "polar", "--start", "2,0,180"], "run.png"),
    "scenario": (["run", "{scenario}", "--no-gif"], "map.png"),
    "batch": (["batch", "amcl_warehouse", "--seeds", "8"], "batch.csv"),
    "localise": (["localize", "{data}/mrclam", "--robot", "1", "--filter", "ekf"], "paths.png"),
    "perceive": (["run", "unexpected_boxes", "--no-gif"], "map.png"),
    "slam": (["map", "{data}/carmen/intel-corrected.log.gz"], "map.png"),
    "foxglove": (["run", "parking", "--mcap", "--no-gif"], "map.png"),
}


def scenario_of_the_page(folder: Path) -> Path:
    """The YAML block of the scenario page, as a file (the page's ``my-run.yaml``)."""
    text = (DOCS / "tasks" / "scenario.rst").read_text(encoding="utf-8")
    block = re.search(r"^\.\. code-block:: yaml\n\n((?:   .*\n|\n)+)", text, re.M).group(1)
    path = folder / "my-run.yaml"
    path.write_text("\n".join(line[3:] for line in block.splitlines()) + "\n")
    return path


def plot_batch(table: Path, png: Path) -> None:
    """The batch page's figure: each seed's final error, true and estimated, from batch.csv."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    with table.open() as handle:
        rows = list(csv.DictReader(handle))
    seeds = [int(row["seed"]) for row in rows]
    fig = Figure(figsize=(6.4, 3.4), layout="constrained")
    ax = fig.add_subplot()
    for key, label, marker in (
        ("final_position_error_true_m", "true", "o"),
        ("final_position_error_estimated_m", "estimated (AMCL)", "x"),
    ):
        values = [float(row[key]) if row.get(key) else float("nan") for row in rows]
        ax.plot(seeds, values, marker, label=label)
    arrived = sum(row["status"] == "arrived" for row in rows)
    ax.set_xlabel("seed")
    ax.set_ylabel("final position error [m]")
    ax.set_title(f"wheelbase batch amcl_warehouse --seeds {len(rows)}: {arrived} arrived")
    ax.grid(True, alpha=0.3)
    ax.legend()
    fig.savefig(png, dpi=100)


def shrink(source: Path, target: Path) -> int:
    """Copy a PNG at most :data:`MAX_WIDTH` wide in 64 colours; return its size [bytes]."""
    from PIL import Image

    with Image.open(source) as image:
        image = image.convert("RGB")
        if image.width > MAX_WIDTH:
            height = round(image.height * MAX_WIDTH / image.width)
            image = image.resize((MAX_WIDTH, height), Image.Resampling.LANCZOS)
        image.quantize(colors=64, method=Image.Quantize.MEDIANCUT).save(target, optimize=True)
    return target.stat().st_size


GIF_BYTES = 450_000
"""Largest animation of the navigate page [bytes]: frames are dropped evenly until it fits."""


def shrink_gif(source: Path, target: Path) -> int:
    """Copy a GIF at most :data:`GIF_WIDTH` pixels wide in one palette of 32 colours (the middle
    frame's), keeping every second frame, or every third … until it is under
    :data:`GIF_BYTES`; return its size [bytes]."""
    from PIL import Image, ImageSequence

    with Image.open(source) as image:
        duration = image.info.get("duration", 66)
        frames = [frame.convert("RGB") for frame in ImageSequence.Iterator(image)]
    if frames[0].width > GIF_WIDTH:
        height = round(frames[0].height * GIF_WIDTH / frames[0].width)
        frames = [frame.resize((GIF_WIDTH, height), Image.Resampling.LANCZOS) for frame in frames]
    palette = frames[len(frames) // 2].quantize(colors=32, method=Image.Quantize.MEDIANCUT)
    frames = [frame.quantize(palette=palette, dither=Image.Dither.NONE) for frame in frames]
    for every in range(2, len(frames) + 1):
        kept = frames[::every]
        kept[0].save(target, save_all=True, append_images=kept[1:], duration=every * duration,
                     loop=0)  # fmt: skip
        if target.stat().st_size <= GIF_BYTES:
            break
    return target.stat().st_size


def animate(name: str, scratch: Path) -> dict:
    """Run a bundled scenario and save its animation as ``docs/images/navigate_NAME.gif``."""
    out = scratch / name
    command = [sys.executable, "-m", "wheelbase", "run", name, "--out", str(out)]
    subprocess.run(command, check=True, capture_output=True, text=True)
    target = IMAGES / f"navigate_{name}.gif"
    return {"file": str(target.relative_to(DOCS.parent)),
            "bytes": shrink_gif(out / "animation.gif", target),
            "command": f"wheelbase run {name}"}  # fmt: skip


def draw(name: str, data: Path, scratch: Path) -> dict:
    """Run the page's command and save its figure as ``docs/images/page_NAME.png``."""
    arguments, shown = PAGES[name]
    out = scratch / name
    filled = [arg.format(scenario=scenario_of_the_page(scratch), data=data) for arg in arguments]
    command = [sys.executable, "-m", "wheelbase", *filled, "--out", str(out)]
    subprocess.run(command, check=True, capture_output=True, text=True)
    figure = out / shown
    if name == "batch":
        figure = out / "batch.png"
        plot_batch(out / shown, figure)
    target = IMAGES / f"page_{name}.png"
    return {"file": str(target.relative_to(DOCS.parent)), "bytes": shrink(figure, target),
            "command": "wheelbase " + " ".join(arguments)}  # fmt: skip


def main(argv: list[str] | None = None) -> list[dict]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", nargs="*", choices=[*sorted(PAGES), "navigate"],
                        help="pages to redraw")  # fmt: skip
    parser.add_argument("--data", type=Path, default=DOCS.parent.parent / "shared/data")
    args = parser.parse_args(argv)
    IMAGES.mkdir(exist_ok=True)
    with tempfile.TemporaryDirectory() as folder:
        pages = args.only or [*PAGES, "navigate"]
        written = [draw(name, args.data, Path(folder)) for name in pages if name in PAGES]
        if "navigate" in pages:
            written += [animate(name, Path(folder)) for name in ANIMATIONS]
    print(json.dumps(written, indent=2))
    return written


if __name__ == "__main__":
    main()
