"""Terrain, payloads and the controllers that cope, in scenarios (issue 24)."""

import copy
import math

import numpy as np
import pytest

from wheelbase.control.adaptive import AdaptiveComputedTorque, step_regressor
from wheelbase.control.traction import TractionControl
from wheelbase.dynamics import RM100
from wheelbase.errors import ConfigError, ScenarioError
from wheelbase.inertial import Payload, inertial_parameters, with_payload
from wheelbase.runner import prepare, run
from wheelbase.scenario import load_scenario
from wheelbase.sim import Stuck, TerrainPlant

STRAIGHT = {
    "name": "straight",
    "map": "empty",
    "robot": {"model": "diffdrive", "preset": "rm100"},
    "plant": "dynamic",
    "controller": {"law": "computed_torque", "gains": {"bandwidth": 1.5}},
    "odometry": {"mode": "encoders", "pulses_per_revolution": 2048},
    "planner": {"reverse": False},
    "start": [0.0, 0.0, 0.0],
    "goal": [4.0, 0.0, 0.0],
    "trajectory": {"max_speed": 0.5, "max_acceleration": 0.4},
    "dt": 0.01,
    "duration": 40.0,
}


def _with(**changes):
    data = copy.deepcopy(STRAIGHT)
    for key, value in changes.items():
        node = data
        *path, last = key.split("__")
        for part in path:
            node = node.setdefault(part, {})
        node[last] = value
    return data


# --------------------------------------------------------------------------- the limits
def test_rigid_floor_without_resistance_reproduces_the_existing_demo_to_the_bit():
    before = run("demo")
    floor = {"like": "dry_concrete", "rolling_resistance": 0.0}
    data = load_scenario("demo").model_dump(mode="json")
    data["terrain"] = {"surface": floor, "slip": False}
    after = run(data)
    assert isinstance(prepare(data).engine.plant, TerrainPlant)
    assert after.log.t.size == before.log.t.size
    assert np.abs(after.log.true_pose - before.log.true_pose).max() <= 1e-9
    assert after.metrics["status"] == before.metrics["status"] == "arrived"


def test_slip_on_dry_concrete_stays_within_three_centimetres_of_rolling():
    # the demo with slip (and the wheels' spin inertia, unknown to the controller) on a floor
    # without rolling resistance: the driven path within 3 cm of the rigid one (1.6 cm measured)
    floor = {"like": "dry_concrete", "rolling_resistance": 0.0}
    data = load_scenario("demo").model_dump(mode="json")
    rigid = run({**data, "terrain": {"surface": floor, "slip": False}})
    slipping = run({**data, "terrain": {"surface": floor, "slip": True}})
    n = min(rigid.log.t.size, slipping.log.t.size)
    gap = np.hypot(*(rigid.log.true_pose[0, :n, :2] - slipping.log.true_pose[0, :n, :2]).T)
    assert slipping.metrics["status"] == "arrived"
    assert 1e-4 < gap.max() < 0.03
    assert np.abs(slipping.log.extras["slip_left"]).max() < 0.05


# --------------------------------------------------------------------------- payloads
def test_a_goal_picks_up_a_payload_the_plant_and_the_controller_know_of():
    data = _with(goals=[[2.0, 0.0, 0.0], {"pose": [4.0, 0.0, 0.0], "payload": None}])
    data.pop("goal")
    data["robot"]["payload"] = {"mass": 20.0, "position": [0.1, 0.0]}
    prepared = prepare(data)
    plant = prepared.engine.plant
    assert plant.model.dynamics.body.mass == pytest.approx(46.2)
    ((time, later),) = plant.changes
    assert later.dynamics.body.mass == pytest.approx(26.2)
    reference = prepared.reference
    at_goal = np.argmin(np.abs(reference.t - time))
    assert np.hypot(*(reference.poses[at_goal, :2] - [4.0, 0.0])) < 0.03
    controller = prepared.engine.controller
    assert controller.model_at(0.0).body.mass == pytest.approx(46.2)
    assert controller.model_at(time + 1).body.mass == pytest.approx(26.2)
    result = run(data)
    assert result.metrics["status"] == "arrived"


def test_the_controller_may_not_know_the_payload():
    data = _with(robot__payload={"mass": 26.2}, controller__model_payload=False)
    prepared = prepare(data)
    assert prepared.engine.plant.model.dynamics.body.mass == pytest.approx(52.4)
    assert prepared.engine.controller.model.body.mass == pytest.approx(26.2)


@pytest.mark.parametrize(
    ("changes", "match"),
    [
        ({"robot__payload": {"mass": -1.0}}, "robot.payload.mass"),
        ({"robot__payload": {"mass": 5.0, "position": [0.9, 0.0]}}, "outside the robot"),
        ({"robot__payload": {"mass": 5.0, "inertia": -1.0}}, "robot.payload.inertia"),
        ({"terrain": {"surface": {"like": "ice", "peak_friction": 0.0}}}, "peak_friction"),
        ({"terrain": {"surface": {"like": "ice", "peak_friction": 0.05}}}, "sliding friction"),
        ({"terrain": {"regions": [{"polygon": [[0, 0], [1, 0], [1, 1]], "surface": "ice",
                                   "grade_percent": 150}]}}, "grade_percent"),
        ({"terrain": {"surface": {"soil": {"n": 3.0, "k_c": 1, "k_phi": 1000, "cohesion": 1,
                                           "friction_angle_deg": 30, "shear_modulus": 0.01}}}},
         "soil.n"),
        ({"terrain": {"regions": [
            {"polygon": [[0, -1], [2, -1], [2, 1], [0, 1]], "surface": "ice"},
            {"polygon": [[1, -1], [3, -1], [3, 1], [1, 1]], "surface": "grass"}]}},
         "regions 0 and 1 overlap"),
        ({"plant": "kinematic", "controller": {"law": "kanayama"}, "terrain": {}},
         "terrain acts on the dynamics"),
        ({"robot__contacts": {"drive_load_share": 1.5}}, "drive_load_share"),
        ({"controller__traction_control": {"friction": -0.2}}, "friction"),
    ],
)  # fmt: skip
def test_bad_ground_and_load_input_names_the_key(changes, match):
    with pytest.raises((ScenarioError, ConfigError), match=match):
        run(_with(**changes))


# --------------------------------------------------------------------------- stuck
def test_stuck_rule_counts_commanded_time_without_motion():
    rule = Stuck(time=1.0, distance=0.1)
    pose = np.zeros((3, 3))
    twist = np.array([[0.0, 0, 0], [0.5, 0, 0], [0.0, 0, 0]])
    reference = np.array([[1.0, 0, 0], [1.0, 0, 0], [0.05, 0, 0]])  # lagging, moving, there
    still = np.zeros(3)
    for _ in range(99):
        still, stuck = rule.update(still, pose, twist, reference, 0.01)
    assert not stuck.any()
    still, stuck = rule.update(still, pose, twist, reference, 0.01)
    assert stuck.tolist() == [True, False, False]


def test_the_rm100_digs_into_dry_sand_and_is_stuck():
    result = run(_with(terrain={"surface": "dry_sand", "stuck_time": 3.0}, duration=20.0))
    assert result.metrics["status"] == "stuck"
    assert result.log.true_pose[0, -1, 0] < 0.2
    assert result.metrics["duration_s"] < 10.0


# --------------------------------------------------------------------------- adaptive
def test_one_steps_regressor_gives_the_torque_that_drove_it():
    body = with_payload(RM100.body, Payload(20.0, (0.1, -0.05), 0.3))
    model = RM100.with_body(body)
    theta = np.r_[inertial_parameters(body), 0.0]
    state, tau, h = np.array([[0.0, 0.0, 0.0, 0.4, 0.0, 0.3]]), np.array([[0.9, 1.3]]), 1e-3
    after = model.step(state, tau, h)
    rows = step_regressor(after[0, [3, 5]], state[0, [3, 5]], h)
    a, d = model.wheel_radius, model.half_track
    force = np.array([tau[0].sum() / a, d * (tau[0, 1] - tau[0, 0]) / a])
    assert rows @ theta == pytest.approx(force, rel=1e-5)


def test_adaptive_computed_torque_learns_an_unknown_payload():
    data = _with(
        goals=[[3.0, 0.0, 90.0], [3.0, 3.0, 180.0], [0.0, 3.0, 0.0]],
        robot__payload={"mass": 26.2, "position": [0.1, 0.0]},
        controller__law="adaptive_computed_torque",
        controller__model_payload=False,
        odometry__mode="perfect",
        duration=80.0,
    )
    data.pop("goal")
    prepared = prepare(data)
    log = prepared.engine.run(prepared.start, seeds=[0])
    truth = inertial_parameters(prepared.engine.plant.model.dynamics.body)
    estimate = prepared.engine.controller.law.estimates[0]
    assert log.statuses == ["arrived"]
    assert estimate[0] == pytest.approx(truth[0], rel=0.02)
    assert estimate[3] == pytest.approx(truth[3], rel=0.05)
    assert estimate[1] == pytest.approx(truth[1], rel=0.1)


def test_adaptive_controller_refuses_bad_options():
    with pytest.raises(ConfigError, match="forgetting"):
        AdaptiveComputedTorque(RM100, forgetting=0.5)
    with pytest.raises(ConfigError, match="filter_time"):
        AdaptiveComputedTorque(RM100, filter_time=0.0)


# --------------------------------------------------------------------------- traction
def test_traction_control_keeps_the_wheels_below_the_peak_slip_on_ice():
    ice = _with(terrain={"surface": "ice"}, trajectory={"max_speed": 0.5, "max_acceleration": 1.0})
    free = run(ice)
    held = run({**ice, "controller": {**ice["controller"],
                                      "traction_control": {"friction": "map"}}})  # fmt: skip
    spin_free = np.abs(free.log.extras["slip_left"]).max()
    spin_held = np.abs(held.log.extras["slip_left"]).max()
    assert spin_free > 0.2
    assert spin_held < 0.1  # ice peaks at σ = 0.06
    assert held.metrics["final_position_error_true_m"] < free.metrics["final_position_error_true_m"]


def test_traction_control_limits_each_wheel_torque():
    class Constant:
        command_names = ("tau_left", "tau_right")

        def __call__(self, t, state, reference):
            return np.tile([3.0, -3.0], (np.shape(state)[0], 1))

    control = TractionControl(Constant(), RM100, friction=0.1, margin=0.8)
    out = control(0.0, np.zeros((2, 6)), None)
    limit = 0.8 * RM100.wheel_radius * 0.1 * 0.5 * RM100.body.mass * 9.80665 / 2
    assert out == pytest.approx(np.tile([limit, -limit], (2, 1)))
    # turning, the lateral force takes its share of the friction circle
    turning = np.array([[0.0, 0.0, 0.0, 0.3, 0.0, 0.5]])
    grip = 0.1 * 0.5 * RM100.body.mass * 9.80665 / 2
    lateral = 0.5 * RM100.body.mass * 0.15
    assert math.isclose(
        control.limits(turning)[0, 0], 0.8 * RM100.wheel_radius * math.sqrt(grip**2 - lateral**2)
    )
    with pytest.raises(ConfigError, match="wheel torques"):
        TractionControl(lambda t, s, r: 0, RM100)


def test_the_torque_window_adds_each_wheels_rolling_moment_to_its_grip():
    # by hand, the RM100 on grass (μ_p 0.24, c_rr 0.10), half its weight on the drive wheels:
    # the ground force F_x is the grip's, |F_x| ≤ 0.8·μ·N; the rolling moment M = c_rr·N·a is
    # the torque's (J·ω̇ = τ − a·F_x − M): driving τ ≤ (0.8·μ + c_rr)·N·a, braking
    # τ ≥ −(0.8·μ − c_rr)·N·a, at rest either way (0.8·μ + c_rr)·N·a
    from wheelbase.terrain import SURFACES, TerrainMap

    class Constant:
        command_names = ("tau_left", "tau_right")

        def __call__(self, t, state, reference):
            return np.tile([3.0, -3.0], (np.shape(state)[0], 1))

    a = RM100.wheel_radius
    load = 0.5 * RM100.body.mass * 9.80665 / 2
    grip, moment = 0.8 * 0.24 * load * a, 0.10 * load * a
    control = TractionControl(
        Constant(), RM100, friction="map", terrain=TerrainMap.uniform(SURFACES["grass"])
    )
    forward = np.array([[0.0, 0.0, 0.0, 0.5, 0.0, 0.0]])
    low, high = control.bounds(forward)
    assert high == pytest.approx(np.full((1, 2), grip + moment))
    assert low == pytest.approx(np.full((1, 2), -(grip - moment)))
    assert (high - moment) / a == pytest.approx(0.8 * 0.24 * load)  # the ground force: the grip
    assert control(0.0, forward, None) == pytest.approx(
        np.array([[grip + moment, -(grip - moment)]])
    )
    low, high = control.bounds(-forward)
    assert high == pytest.approx(np.full((1, 2), grip - moment))
    assert low == pytest.approx(np.full((1, 2), -(grip + moment)))
    low, high = control.bounds(np.zeros((1, 6)))
    assert high == pytest.approx(np.full((1, 2), grip + moment))
    assert low == pytest.approx(np.full((1, 2), -(grip + moment)))
    # on the spot at 1 rad/s: the left wheel rolls back, the right ahead, both at d·r = 0.23 m/s
    spin = np.array([[0.0, 0.0, 0.0, 0.0, 0.0, 1.0]])
    low, high = control.bounds(spin)
    assert high == pytest.approx(np.array([[grip - moment, grip + moment]]))
    assert low == pytest.approx(np.array([[-(grip + moment), -(grip - moment)]]))
    # where c_rr exceeds margin·μ the window still holds 0: no braking torque is turned into drive
    sticky = TractionControl(Constant(), RM100, friction=0.1, rolling_resistance=0.09)
    low, high = sticky.bounds(forward)
    assert low == pytest.approx(np.array([[0.0, 0.0]]))
    assert high == pytest.approx(np.full((1, 2), (0.08 + 0.09) * load * a))
    assert sticky(0.0, forward, None)[0, 1] == 0.0
    with pytest.raises(ConfigError, match="rolling_resistance"):
        TractionControl(Constant(), RM100, friction="map", rolling_resistance=0.1,
                        terrain=TerrainMap.uniform(SURFACES["grass"]))  # fmt: skip
    # with the estimate the robot's own c_rr: its window counts the moment, its estimate not
    told = TractionControl(Constant(), RM100, friction="estimate", rolling_resistance=0.1)
    assert told.estimator.rolling_resistance == 0.1
    low, high = told.bounds(forward)
    assert high == pytest.approx(np.full((1, 2), 0.8 * 1.0 * load * a + moment))
    with pytest.raises(ConfigError, match="rolling_resistance"):
        TractionControl(Constant(), RM100, friction=0.2, rolling_resistance=-0.1)


def test_traction_control_on_grass_accelerates_at_the_grip_its_casters_leave():
    # 4 m straight on grass asking 1 m/s²: the torques at the window's edge give each wheel the
    # ground force 0.8·μ_p·N; the casters take c_rr·(1 − s)·m·g and the wheels' spin inertia
    # J_w/a² each: u̇ = (2·0.8·μ_p·N − c_rr·(1 − s)·m·g)/(m + 2·J_w/a²). A clip of 0.8·μ_p·N·a
    # alone left 2·(0.8·μ_p − c_rr)·N = 11.8 N against the casters' 12.8 N: no motion at all
    from wheelbase.terrain import SURFACES

    grass = SURFACES["grass"]
    data = _with(terrain={"surface": "grass"}, trajectory={"max_speed": 0.5,
                                                          "max_acceleration": 1.0})  # fmt: skip
    free = run(copy.deepcopy(data))
    data["controller"]["traction_control"] = {"friction": "map"}
    held = run(data)
    m, g, a, jw = RM100.body.mass, 9.80665, RM100.wheel_radius, 0.01
    load = 0.5 * m * g / 2
    expected = (2 * 0.8 * grass.peak_friction * load - grass.rolling_resistance * 0.5 * m * g) / (
        m + 2 * jw / a**2
    )
    n = int(held.log.length[0])
    u, t = held.log.twist[0, :n, 0], held.log.t[:n]
    accel = (u[10:] - u[:-10]) / (t[10:] - t[:-10])  # the true speed's, over 0.1 s
    assert accel.max() == pytest.approx(expected, rel=0.03)
    assert held.metrics["max_slip"] < 0.1 < free.metrics["max_slip"]  # grass peaks at 0.2
    assert held.metrics["distance_travelled_m"] > 3.8
    assert (
        held.metrics["final_position_error_true_m"]
        <= free.metrics["final_position_error_true_m"] + 1e-3
    )


# --------------------------------------------------------------------------- raster
def test_a_raster_of_surfaces_lies_under_the_regions(tmp_path):
    from PIL import Image

    from wheelbase.scenario_ground import build_terrain

    pixels = np.full((20, 40), 255, np.uint8)  # 2 m × 4 m at 0.1 m: concrete
    pixels[:, 20:] = 128  # the right half (x > 2 m) ice
    pixels[:10, :] = 0  # the top half (y > 1 m, image rows at the top) sand
    Image.fromarray(pixels).save(tmp_path / "floor.png")
    raster = {"image": "floor.png", "resolution": 0.1, "origin": [0.0, -1.0],
              "legend": {255: "dry_concrete", 128: "ice", 0: "dry_sand"}}  # fmt: skip
    region = {"polygon": [[0.2, -0.8], [0.6, -0.8], [0.6, -0.4], [0.2, -0.4]], "surface": "grass"}
    data = _with(terrain={"raster": raster, "regions": [region]})
    (tmp_path / "s.yaml").write_text(__import__("yaml").safe_dump(data))
    scenario = load_scenario(tmp_path / "s.yaml")  # the image is found beside the file
    terrain = build_terrain(scenario, prepare(scenario).grid)
    names = terrain.names
    assert names[int(terrain.index([1.0, -0.5]))] == "dry_concrete"
    assert names[int(terrain.index([3.0, -0.5]))] == "ice"
    assert names[int(terrain.index([1.0, 0.5]))] == "dry_sand"
    assert names[int(terrain.index([0.4, -0.6]))] == "grass"  # the region over the raster
    data["terrain"]["raster"]["legend"] = {255: "dry_concrete"}
    (tmp_path / "s.yaml").write_text(__import__("yaml").safe_dump(data))
    with pytest.raises(ScenarioError, match="grey level 0 of the image has no surface"):
        run(tmp_path / "s.yaml")


def test_estimated_friction_learns_ice_from_the_encoders_alone(monkeypatch):
    # the 4 m straight at 1 m/s² on ice: the first spin teaches the robot the ice (its rim
    # outruns the body its torques push), the estimate lands between ice's sliding (0.07) and
    # its peak (0.1), and no wheel spins again until the estimate's memory (5 m) runs out and
    # it probes the peak again
    from wheelbase import scenario_ground

    ice = _with(terrain={"surface": "ice"}, trajectory={"max_speed": 0.5, "max_acceleration": 1.0})
    ice["controller"]["traction_control"] = {"friction": "estimate"}
    prepared = prepare(ice)
    log = prepared.engine.run(prepared.start, seeds=[0])
    estimator = prepared.engine.controller.estimator
    assert estimator.spins, "the first spin is detected"
    first_end, _robot, _wheel, learnt = estimator.spins[0]
    assert first_end < 0.5 and 0.06 <= learnt <= 0.1
    probe = estimator.spins[2][0] - 0.5 if len(estimator.spins) > 2 else np.inf
    after = (log.t > first_end + 0.1) & (log.t < probe)
    assert log.t[after][-1] > 5.0
    slip = np.abs(np.concatenate([log.extras["slip_left"][0, after],
                                  log.extras["slip_right"][0, after]]))  # fmt: skip
    assert slip.max() < 0.05  # ice peaks at 0.06
    # it never reads the terrain: the same run with the map hidden from the controller
    original = scenario_ground.wrap_controller

    def hidden(scenario, controller, robot, timeline, terrain=None):
        return original(scenario, controller, robot, timeline, None)

    monkeypatch.setattr(scenario_ground, "wrap_controller", hidden)
    again = prepare(ice)
    blind = again.engine.run(again.start, seeds=[0])
    assert np.array_equal(blind.true_pose, log.true_pose)
    assert np.array_equal(blind.torques, log.torques)


def test_estimated_friction_raises_no_alarm_on_concrete_with_an_unknown_payload():
    # heavier than its model (+100 %), a robot's wheels turn slower than the model says:
    # the opposite of a spin; the torques are those of the run without traction control
    data = _with(terrain={"surface": "dry_concrete"},
                 robot={"model": "diffdrive", "preset": "rm100",
                        "payload": {"mass": 26.2, "position": [0.1, 0.0]}})  # fmt: skip
    free = run(copy.deepcopy(data))
    data["controller"]["traction_control"] = {"friction": "estimate"}
    prepared = prepare(data)
    log = prepared.engine.run(prepared.start, seeds=[0])
    assert prepared.engine.controller.estimator.spins == []
    assert np.array_equal(log.torques, free.log.torques)


def test_traction_control_holding_the_integrators_overshoots_less_on_ice():
    # the clipped torques wind the PID's integrators up: the robot overshoots its reference's
    # 0.6 m/s (when the clip also counted the rolling moment against the grip it reached
    # 1.4 m/s, skidded in a turn and hit a wall); with the law's saturation at the window's
    # edge its anti-windup holds and the peak speed is lower. Neither collides, the wheels stay
    # below ice's peak slip; both creep to a stop short of the goal (a lateral error that a
    # differential drive cannot close at rest), within half a metre
    data = load_scenario("demo").model_dump(mode="json")
    data["terrain"] = {"surface": "ice"}
    data["controller"]["traction_control"] = {"friction": "map"}
    before = run(copy.deepcopy(data))
    data["controller"]["traction_control"]["hold_integrators"] = True
    after = run(data)

    def peak_speed(result):
        return np.abs(result.log.twist[0, : int(result.log.length[0]), 0]).max()

    assert peak_speed(after) < peak_speed(before)
    for result in (before, after):
        assert result.metrics["status"] != "collision"
        assert result.metrics["max_slip"] < 0.1
        assert result.metrics["final_position_error_true_m"] < 0.5
