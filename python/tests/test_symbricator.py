"""pytest tests of the Python module `symbricator` (python/symbricator_module.cpp; docs/python.md).

Run by CTest (python.pytest, release builds) with PYTHONPATH at the build's python/ folder and
SYMB_BINARY, SYMB_SCENARIO_DIR set.
"""
import math
import os
import pathlib
import subprocess

import numpy as np
import pytest

import symbricator as symb

SCENARIOS = pathlib.Path(os.environ.get("SYMB_SCENARIO_DIR", pathlib.Path(__file__).parents[2] / "scenarios"))
MAZE = str(SCENARIOS / "maze.yaml")
WHEELS = [symb.STEP_COLUMNS.index("left_cm_s"), symb.STEP_COLUMNS.index("right_cm_s")]


def symb_run_hash(scenario, *args):
    out = subprocess.run([os.environ["SYMB_BINARY"], "run", scenario, "--print-hash", "--quiet", *args],
                         check=True, capture_output=True, text=True).stdout
    return int(out.split("trajectory-hash:")[1].split()[0], 16)


def test_maze_from_python_has_symb_runs_trajectory_hash():
    whole = symb.Simulation(MAZE, duration=60)
    whole.run()
    assert whole.steps_run == 2000
    assert whole.trajectory_hash == symb_run_hash(MAZE, "--duration", "60s")
    # In steps and slices: the same run.
    sliced = symb.Simulation(MAZE, duration=60)
    sliced.step(7)
    sliced.run(seconds=12.5)
    sliced.run()
    assert sliced.trajectory_hash == whole.trajectory_hash
    assert sliced.time == pytest.approx(60.0)


def test_results_are_numpy_blocks(tmp_path):
    subprocess.run([os.environ["SYMB_BINARY"], "run", MAZE, "--duration", "30s", "--quiet", "--out",
                    str(tmp_path / "out")], check=True)
    sim = symb.Simulation(MAZE, duration=30)
    sim.run()
    steps = sim.steps()
    assert steps.dtype == np.float64 and steps.shape == (1000, len(symb.STEP_COLUMNS))
    assert steps.flags["C_CONTIGUOUS"] and steps.flags["OWNDATA"]
    t = sim.trajectory(0)
    np.testing.assert_array_equal(t, steps[:, 2:5])
    # steps.csv's columns, in its order, and its values (to its printed decimals).
    csv_columns = (tmp_path / "out" / "steps.csv").read_text().splitlines()[0].split(",")
    assert symb.STEP_COLUMNS[:len(csv_columns)] == csv_columns
    csv = np.loadtxt(tmp_path / "out" / "steps.csv", delimiter=",", skiprows=1,
                     converters={1: lambda s: 0.0}, encoding="utf-8")
    np.testing.assert_allclose(steps[:, :len(csv_columns)], csv, rtol=0, atol=0.051)
    # The robot drove: time column is the control period's multiples, distance grows.
    np.testing.assert_allclose(steps[:, 0], 0.03 * np.arange(1, 1001), rtol=0, atol=1e-9)
    assert steps[-1, symb.STEP_COLUMNS.index("distance_cm")] > 100


def test_probes_arrive_as_arrays():
    sim = symb.Simulation(str(SCENARIOS / "ahhs_obstacle_avoidance.yaml"), duration=5)
    sim.run()
    probes = sim.probes()
    assert probes
    for (robot, task, channel), (times, values) in probes.items():
        assert times.ndim == 1 and values.shape[0] == times.shape[0]
        assert np.all(np.diff(times) >= 0)


def test_spikes_arrive_as_arrays():
    sim = symb.Simulation(str(SCENARIOS / "linda_maze.yaml"), duration=3)
    sim.run()
    spikes = sim.spikes()
    assert set(spikes) == {("thymio", "controller", "spikes")}
    times, values = spikes["thymio", "controller", "spikes"]
    assert times.shape[0] > 10 and values.shape[0] == times.shape[0]
    # The same samples as among all probes.
    np.testing.assert_array_equal(sim.probes()["thymio", "controller", "spikes"][1], values)


def test_a_live_node_is_rewired_from_python():
    sim = symb.Simulation(MAZE, duration=20)
    robot = sim.robot("thymio")
    sim.run(seconds=2)
    robot.suspend("controller")
    sim.run(seconds=2)
    # The wheels' watchdog stopped the robot 45 ms after the last command.
    assert np.all(sim.steps()[-10:, WHEELS] == 0)
    robot.resume("controller")
    # A second controller of a registered type, hooked in, its parameter changed while it runs.
    robot.create("mdl2e", "c2", program="mdl2e/obstacle_avoidance.mdl2e")
    robot.hook("ir", "c2")
    robot.set("c2", "speed_limit", 100)
    sim.step()  # the task takes the value on its own context
    assert float(robot.parameters("c2")["speed_limit"]) == 100
    robot.post("wheels", [50, -50])
    assert "c2" in robot.shell("tasks")
    sim.run()
    states = {t["name"]: t["state"] for t in robot.tasks()}
    assert states["controller"] == "running" and states["c2"] == "running"


def test_cpp_errors_are_python_exceptions_with_their_location(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text(MAZE_TEXT.replace("type: mdl2e", "type: mdl2f"))
    with pytest.raises(symb.Error) as e:
        symb.Simulation(str(bad))
    assert str(bad) in str(e.value) and "mdl2f" in str(e.value) and "did you mean" in str(e.value)
    robot = symb.Simulation(MAZE, duration=1).robot(0)
    with pytest.raises(symb.Error, match="column"):
        robot.shell("create mdl2e c3 speed_limit=-1")
    with pytest.raises(symb.Error, match="no task 'nobody'"):
        robot.suspend("nobody")


MAZE_TEXT = pathlib.Path(MAZE).read_text() if pathlib.Path(MAZE).exists() else ""


class Drive:
    """drives straight on every IR reading"""

    def __init__(self):
        self.readings = 0

    def on_message(self, task, port, values):
        self.readings += 1
        task.send([250.0, 250.0])


def test_a_python_task_type_drives_the_robot(tmp_path):
    text = MAZE_TEXT.replace("type: mdl2e", "type: py_drive").replace(
        "params: {program: mdl2e/obstacle_avoidance.mdl2e}", "")
    (tmp_path / "py.yaml").write_text(text)
    sim = symb.Simulation(str(tmp_path / "py.yaml"), duration=3, types={"py_drive": Drive})
    sim.run()
    # 250 motor units = 10 cm/s for 3 s, less the start.
    assert 20 < sim.steps()[-1, symb.STEP_COLUMNS.index("distance_cm")] < 31


class Faulty:
    def __init__(self):
        self.ticks = 0

    def on_tick(self, task):
        self.ticks += 1
        if self.ticks == 3:
            raise ValueError("third tick")


def test_a_python_exception_faults_that_task_only():
    sim = symb.Simulation(MAZE, duration=10)
    robot = sim.robot(0)
    faulty = Faulty()
    robot.add_task("faulty", faulty, period=0.1)
    sim.run()
    states = {t["name"]: t["state"] for t in robot.tasks()}
    assert states["faulty"] == "faulted"
    assert faulty.ticks == 3
    assert states["controller"] == "running"
    assert sim.time == pytest.approx(10.0)
    # The robot drove on to the end: the last second's steps still move.
    assert np.any(sim.steps()[-30:, WHEELS] != 0)
    log = robot.shell("log")
    assert "third tick" in log and "ValueError" in log


class OnePlusOneFitness:
    """(1+1)-ONLINE's fitness, as the built-in `fitness` task computes it (evo/fitness/fitness.hpp)"""

    def __init__(self):
        self.command = (0.0, 0.0)
        self.command_time = -math.inf
        self.sum = 0.0
        self.steps = 0

    def on_message(self, task, port, values):
        if len(values) == 2:
            self.command, self.command_time = tuple(values), task.now
            return
        left, right = self.command if task.now - self.command_time <= 0.1 else (0.0, 0.0)
        clamp = lambda v, lo, hi: min(max(v, lo), hi)
        left, right = clamp(left / 500, -1, 1), clamp(right / 500, -1, 1)
        i = max((clamp(r / 4505, 0, 1) for r in values), default=0.0)
        step = abs(left + right) / 2 * (1 - abs(left - right) / 2) * (1 - i)
        self.sum += step
        self.steps += 1
        task.send([self.sum, float(self.steps), step])


def evolve_scenario(tmp_path, fitness_type):
    text = (SCENARIOS / "evolve_maze.yaml").read_text()
    text = text.replace("duration: 120min", "duration: 40s")
    text = text.replace("evaluation: 20s, recovery: 1s", "evaluation: 3s, recovery: 0.5s")
    text = text.replace("type: fitness\n        params: {formula: one_plus_one, every: 5}",
                        "type: " + fitness_type + ("\n        params: {formula: one_plus_one}" if fitness_type == "fitness" else ""))
    path = tmp_path / (fitness_type + ".yaml")
    path.write_text(text)
    return str(path)


def evaluations(sim):
    return [v[0] for (robot, task, channel), (t, values) in sim.probes("fitness").items()
            if task == "evolution" for v in values]


def test_a_python_fitness_drives_one_plus_one_online(tmp_path):
    py = symb.Simulation(evolve_scenario(tmp_path, "py_fitness"), types={"py_fitness": OnePlusOneFitness})
    py.run()
    cpp = symb.Simulation(evolve_scenario(tmp_path, "fitness"))
    cpp.run()
    got, want = evaluations(py), evaluations(cpp)
    assert len(got) >= 8
    # The same formula in Python: the same evaluations, to float precision.
    np.testing.assert_allclose(got[:len(want)], want[:len(got)], rtol=1e-5, atol=1e-6)


def test_one_plus_one_from_a_python_loop():
    target = np.linspace(-1, 1, 5)

    def evolve(seed):
        es = symb.OnePlusOne(genes=5, lo=-2, hi=2, sigma=0.5, sigma_max=1, seed=seed)
        first = None
        for _ in range(300):
            genes = es.next()
            fitness = -float(np.sum((genes - target) ** 2))
            first = fitness if first is None else first
            es.report(fitness)
        return first, es.champion_fitness

    first, best = evolve(3)
    assert best > first
    assert evolve(3) == (first, best)  # same seed, same run


def test_mu_plus_one_from_a_python_loop():
    target = np.linspace(-1, 1, 4)
    es = symb.MuPlusOne(genes=4, lo=-2, hi=2, mu=5, sigma=0.3, seed=2)
    with pytest.raises(symb.Error, match="no report yet"):
        es.best_fitness
    firsts = []
    for i in range(400):
        fitness = -float(np.sum((es.next() - target) ** 2))
        if i < 5:
            firsts.append(fitness)
        es.report(fitness)
    assert es.best_fitness > max(firsts)
    assert es.best_fitness == -float(np.sum((es.best - target) ** 2))
