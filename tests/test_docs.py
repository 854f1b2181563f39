"""The documentation site builds, warnings as errors and nitpicky (every cross-reference
resolves; the quick build: examples not run)."""

import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("sphinx")
pytest.importorskip("numpydoc")
pytest.importorskip("sphinx_gallery")
pytest.importorskip("furo")

DOCS = Path(__file__).resolve().parents[1] / "docs"


def test_quick_build_has_no_warning_and_documents_the_api(tmp_path):
    out = tmp_path / "html"
    done = subprocess.run(
        [sys.executable, "-m", "sphinx", "-n", "-W", "--keep-going", "-q", "-b", "html",
         "-D", "plot_gallery=0", "-d", str(tmp_path / "doctrees"), str(DOCS), str(out)],
        capture_output=True, text=True, timeout=600, check=False,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-4000:]
    # Every task page and the comparison page are there, and the API pages hold the objects.
    for page in ("simulate", "plan", "control", "scenario", "batch", "localise", "foxglove",
                 "gymnasium"):  # fmt: skip
        assert (out / "tasks" / f"{page}.html").is_file()
    assert "plannerHybridAStar" in (out / "coming_from.html").read_text()
    api = {
        "models": "wheelbase.models.DiffDrive",
        "planning": "wheelbase.planning.HybridAStar",
        "sim": "wheelbase.sim.Engine",
        "gym": "wheelbase.gym.NavigateVectorEnv",
        "mcap_export": "wheelbase.mcap_export.write_mcap",
        "localization": "wheelbase.localization.mrclam.localize",
        "limits": "wheelbase.limits.MAX_STEPS",
    }
    for page, anchor in api.items():
        assert f'id="{anchor}"' in (out / "api" / f"{page}.html").read_text(), anchor
    assert (
        'id="wheelbase.localization.mrclam.MRCLAM_PARAMETERS"'
        in (out / "api" / "localization.html").read_text()
    )
    # A re-export links to where it is documented (wheelbase.run → wheelbase.runner.run).
    assert (
        'href="../api/runner.html#wheelbase.runner.run"'
        in (out / "tasks" / "scenario.html").read_text()
    )
    gallery = {path.stem for path in (out / "auto_examples").glob("*.html")}
    scripts = {path.stem for path in (DOCS.parent / "examples").glob("*.py")}
    assert scripts - {"gym_ppo"} <= gallery


# Nav2's AMCL parameters (nav2_amcl, the parameters page of the Nav2 documentation)
NAV2_AMCL = {
    "alpha1", "alpha2", "alpha3", "alpha4", "alpha5", "base_frame_id", "beam_skip_distance",
    "beam_skip_error_threshold", "beam_skip_threshold", "do_beamskip", "global_frame_id",
    "lambda_short", "laser_likelihood_max_dist", "laser_max_range", "laser_min_range",
    "laser_model_type", "set_initial_pose", "initial_pose", "max_beams", "max_particles",
    "min_particles", "odom_frame_id", "pf_err", "pf_z", "recovery_alpha_fast",
    "recovery_alpha_slow", "resample_interval", "robot_model_type", "save_pose_rate",
    "sigma_hit", "tf_broadcast", "transform_tolerance", "update_min_a", "update_min_d", "z_hit",
    "z_max", "z_rand", "z_short", "scan_topic", "map_topic",
}  # fmt: skip


def test_the_nav2_amcl_mapping_names_real_parameters_on_both_sides():
    # the page said AMCL takes "the same names" as nav2_amcl: it lists each name now, and a name
    # said to be the same must be the same
    import re

    from wheelbase.localization import AMCL, OdometryMotion
    from wheelbase.sensors import Lidar

    text = (DOCS / "coming_from.rst").read_text()
    assert "the same\nnames" not in text and "(the same names" not in text
    table = text[text.index("``nav2_amcl`` parameters and their names") :]
    rows = re.findall(r"^(``\S.*?)\s{2,}(``.*?``)\s{2,}(.*)$", table, re.M)
    assert len(rows) >= 15
    owners = {"motion": OdometryMotion, "lidar": Lidar}
    for nav2, ours, note in rows:
        nav2_names = re.findall(r"``(\w+)``", nav2)
        our_names = re.findall(r"``([\w.]+)``", ours)
        assert set(nav2_names) <= NAV2_AMCL | {"nav2_amcl"}, nav2
        owner = ""
        for name in our_names:  # "motion.alpha1 … alpha4": alpha4 is the motion model's too
            owner, _, attribute = name.rpartition(".") if "." in name else (owner, ".", name)
            cls = owners.get(owner, AMCL)
            assert attribute in cls.__dataclass_fields__ or hasattr(cls, attribute), name
        if note.startswith("same name"):
            assert [n.split(".")[-1] for n in our_names] == nav2_names[: len(our_names)]


def test_the_localise_page_says_what_was_fitted_on_which_robot():
    # it said one parameter set "serves every robot" with no figure for any robot but 1
    import re

    text = (DOCS / "tasks" / "localise.rst").read_text()
    assert "fitted on **robot 1 of data set 6** alone" in text
    rows = dict(
        re.findall(r"^(robot \d)[^\n]*?\s{2,}([\d.]+ m\s+[\d.]+ m\s+[\d.]+ m)$", text, re.M)
    )
    assert set(rows) == {"robot 1", "robot 2", "robot 3"}
    assert rows["robot 2"].split()[::2] == ["0.150", "0.125", "0.130"]
    assert rows["robot 3"].split()[::2] == ["0.108", "0.091", "0.093"]
    # robot 1's row is the figures the page reports for it
    ekf, ukf, pf = rows["robot 1"].split()[::2]
    assert f"EKF {ekf} m RMSE" in text and f"UKF {ukf} m (" in text and f"PF {pf} m (" in text


def test_the_home_page_and_every_task_page_show_the_figure_of_their_command():
    # seven of eight task pages and the home page had no figure
    import importlib.util
    import re

    spec = importlib.util.spec_from_file_location("make_images", DOCS / "make_images.py")
    make_images = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(make_images)
    tasks = {page.stem for page in (DOCS / "tasks").glob("*.rst")}
    assert set(make_images.PAGES) <= {"index"} | tasks
    for page in ["index", *sorted(tasks)]:
        source = DOCS / ("index.rst" if page == "index" else f"tasks/{page}.rst")
        figures = re.findall(r"^\.\. (?:figure|image):: (\S+)", source.read_text(), re.M)
        assert figures, page
        for figure in figures:
            image = (source.parent / figure).resolve()
            if image.suffix == ".gif":  # the navigate page's animations
                assert image.read_bytes()[:4] == b"GIF8", figure
                assert image.stat().st_size <= make_images.GIF_BYTES, f"{figure}: too large"
                continue
            assert image.read_bytes()[:4] == b"\x89PNG", figure
            assert image.stat().st_size < 100_000, f"{figure}: keep the repository small"
