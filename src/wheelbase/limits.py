"""Resource limits: the largest problems wheelbase takes on before refusing with a clear error.

A typo in a file (``dt: 1e-9``, a goal 1e6 m away, a 1e9 m wheel base) must not become an
hour-long loop or a request for terabytes of memory. Each limit below is the default of a
keyword (or scenario key) that raises it, and the error that enforces it names both, e.g.
``duration / dt = 1.2e+11 steps: more than resources.max_steps = 1000000``.

=========================  ============================================  ===========================
limit                      what it bounds (default)                      raised by
=========================  ============================================  ===========================
``MAX_STEPS``              closed-loop steps duration / dt (1e6: 28 h    scenario
                           at 0.1 s, 17 min at 1 ms)                     ``resources.max_steps``
``MAX_MAP_CELLS``          cells of an occupancy grid (1e8: 10 km × 10   scenario
                           km at 1 m, 500 m square at 5 cm; its          ``resources.max_map_cells``
                           distance field alone is 0.8 GB)
``MAX_STATE_BINS``         Hybrid A* state bins x × y × heading (5e7:    ``HybridAStar(...,
                           the search's arrays take ~0.5 GB)             max_state_bins=)``
``MAX_SAMPLE_STEPS``       MPPI samples × horizon steps per call (1e7:   ``MPPI(...,
                           1.6 GB and ~4 s per NumPy call; a GPU takes   max_sample_steps=)``
                           1e8 when asked)
``MAX_COORDINATE``         x and y of poses in scenario files, within    fixed: float64 spacing
                           ±1e10 m (UTM-like and beyond)                 is 2 µm there
``MAX_BEAMS``              beams of one lidar scan (1e5: 0.0036° apart,  fixed: no lidar comes
                           60× finer than a 0.2° scanner)                near it
``MAX_PARTICLES``          particles of a particle filter (1e6: 24 MB;   fixed
                           an update of 60 beams takes seconds)
``MAX_FALSE_RATE``         mean false landmark detections per scan       fixed
                           (1e3)
``MAX_SEEDS``              seeds of one batch (1e6 runs per scenario)    fixed
``MAX_PATH_POINTS``        points of a densified reference path (1e7:    fixed
                           500 km at MPPI's 5 cm)
``MAX_PRIMITIVE_SAMPLES``  collision samples of Hybrid A*'s motion       fixed
                           primitives, and of one escape move (1e7: 240
                           MB)
``MAX_TRACKS``             tracks one obstacle tracker keeps (1e4: its   scenario
                           association matrix is 1e4 × beams)            ``tracker.max_tracks``
``BATCH_MEMORY``           bytes the logs of the seeds run together in   ``run_batch(...,
                           one vectorised chunk may take (512 MiB; only  memory_budget=)``,
                           each finished run's metrics are kept)         ``batch --memory-mb``
=========================  ============================================  ===========================
"""

from __future__ import annotations

__all__ = [
    "BATCH_MEMORY",
    "MAX_BEAMS",
    "MAX_COORDINATE",
    "MAX_FALSE_RATE",
    "MAX_MAP_CELLS",
    "MAX_PARTICLES",
    "MAX_PATH_POINTS",
    "MAX_PRIMITIVE_SAMPLES",
    "MAX_SAMPLE_STEPS",
    "MAX_SEEDS",
    "MAX_STATE_BINS",
    "MAX_STEPS",
    "MAX_TRACKS",
]

MAX_STEPS = 1_000_000
"""Most closed-loop steps duration / dt (scenario ``resources.max_steps``)."""
MAX_MAP_CELLS = 100_000_000
"""Most cells of an occupancy grid (scenario ``resources.max_map_cells``)."""
MAX_STATE_BINS = 50_000_000
"""Most Hybrid A* state bins x × y × heading (``HybridAStar(..., max_state_bins=)``)."""
MAX_SAMPLE_STEPS = 10_000_000
"""Most MPPI samples × horizon steps per call (``MPPI(..., max_sample_steps=)``)."""
MAX_COORDINATE = 1.0e10  # m
"""Largest |x|, |y| [m] of a pose in a file."""
MAX_BEAMS = 100_000
"""Most beams of one lidar scan."""
MAX_PARTICLES = 1_000_000
"""Most particles of a particle filter."""
MAX_FALSE_RATE = 1_000.0  # per scan
"""Largest mean number of false landmark detections per scan."""
MAX_SEEDS = 1_000_000
"""Most seeds of one batch."""
MAX_PATH_POINTS = 10_000_000
"""Most points of a densified reference path."""
MAX_PRIMITIVE_SAMPLES = 10_000_000
"""Most collision samples of Hybrid A*'s motion primitives and of one escape move."""
MAX_TRACKS = 10_000
"""Most tracks one obstacle tracker keeps (scenario ``tracker.max_tracks``)."""
BATCH_MEMORY = 512 * 2**20  # bytes
"""Bytes the logs of one vectorised chunk of seeds may take (``run_batch(..., memory_budget=)``)."""
