"""The Python slow path and the bindings' result arrays, measured (bench/README.md, "python_bench").

    PYTHONPATH=build/python python3 bench/python/python_bench.py --plugin PATH/libmy_controller.so

1. Braitenberg in Python vs in C++: the same controller (examples/my_controller's my_braitenberg,
   a plugin; BraitenbergPy below, the same arithmetic in Python) drives the robot of
   examples/my_controller/my_controller.yaml for 10 simulated minutes; the real-time factor of each,
   measured in one run, and whether the two trajectories are the same.
2. Result arrays: Simulation.steps() for a 10-minute run (20,000 steps x 16 columns) against a bare
   numpy copy of the same number of bytes, and against building the same rows element by element
   in Python (what the bindings must not do).
No target: the figures are reported.
"""
import argparse
import pathlib
import statistics
import time

import numpy as np

import symbricator as symb

ROOT = pathlib.Path(__file__).resolve().parents[2]
SCENARIO = ROOT / "examples" / "my_controller" / "my_controller.yaml"
LEFT = (1.0, 0.8, 0.4, -0.8, -1.0)


class BraitenbergPy:
    """my_braitenberg in Python (examples/my_controller/my_controller.cpp)"""

    speed, gain, range = 250.0, 1.5, 4505.0

    def on_message(self, task, port, ir):
        if port != 0 or len(ir) < 7:
            return
        turn = 0.0
        for w, r in zip(LEFT, ir):
            turn += w * min(max(r / self.range, 0.0), 1.0)
        forward = self.speed * (1.0 - min(max(ir[2] / self.range, 0.0), 1.0))
        steer = self.gain * self.speed * turn
        task.send([forward + steer, forward - steer])


def timed_run(make):
    sim = make()
    start = time.perf_counter()
    sim.run()
    wall = time.perf_counter() - start
    return sim, sim.time / wall


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--plugin", required=True, help="libmy_controller.so (examples/my_controller built)")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()

    py_text = SCENARIO.read_text().replace("type: my_braitenberg", "type: py_braitenberg").replace(
        "params: {speed: 250, gain: 1.5}", "")
    py_file = pathlib.Path("/tmp") / "python_bench_braitenberg.yaml"
    py_file.write_text(py_text)
    cpp_rtf, py_rtf = [], []
    for _ in range(args.repeat):
        cpp, rtf = timed_run(lambda: symb.Simulation(str(SCENARIO), duration=600, plugins=[args.plugin]))
        cpp_rtf.append(rtf)
        py, rtf = timed_run(lambda: symb.Simulation(str(py_file), duration=600, types={"py_braitenberg": BraitenbergPy}))
        py_rtf.append(rtf)
    c, p = statistics.median(cpp_rtf), statistics.median(py_rtf)
    print(f"braitenberg 10 min: C++ plugin real-time factor {c:,.0f}, Python {p:,.0f}: Python is {c / p:.1f}x slower "
          f"(median of {args.repeat}); same trajectory: {cpp.trajectory_hash == py.trajectory_hash}")

    steps = cpp.steps()
    n = steps.size
    reps = 50
    t0 = time.perf_counter()
    for _ in range(reps):
        cpp.steps()
    t_steps = (time.perf_counter() - t0) / reps
    t0 = time.perf_counter()
    for _ in range(reps):
        steps.copy()
    t_copy = (time.perf_counter() - t0) / reps
    flat = steps.ravel().tolist()
    t0 = time.perf_counter()
    np.array([float(v) for v in flat]).reshape(steps.shape)
    t_elem = time.perf_counter() - t0
    print(f"steps() of a 10 min run: {steps.shape[0]} x {steps.shape[1]} = {n:,} values in {t_steps * 1e3:.3f} ms "
          f"({t_steps / n * 1e9:.2f} ns per value); a bare numpy copy {t_copy * 1e3:.3f} ms "
          f"(ratio {t_steps / t_copy:.2f}); element by element in Python {t_elem * 1e3:.1f} ms "
          f"({t_elem / t_steps:.0f}x steps())")


if __name__ == "__main__":
    main()
