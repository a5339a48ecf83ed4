"""Side-by-side with IR-SIM: MRComm's simulation speed against a lightweight Python robot
simulator's, at the same team size and the same 0.1 s step, on one core.

IR-SIM (PyPI ``ir-sim``, pinned below) runs in its own virtualenv, made on first use in
``benchmarks/.irsim-venv`` (not a dependency of MRComm), headless, with no rendering:
``N`` differential-drive robots of MRComm's radius and speed limits, placed at random in
an open square of ~25 m² per robot, each driving to a random goal with IR-SIM's ``rvo``
behaviour (reciprocal velocity obstacles: robots avoid each other, the counterpart of
MRComm's navigation around mates) and, for reference, ``dash`` (straight to the goal, no
avoidance; colliding robots stop). IR-SIM has no map planning, no network and no agents;
MRComm runs the generated scenarios of ``bench_scale.py`` (map planning, WLAN with 25 %
loss, NB agents, every message). Each case runs in a fresh process pinned to one core,
cases interleaved over ``--repeats`` rounds; the median real-time factor is reported
with the ratio MRComm / IR-SIM.

With ``--options JSON`` MRComm runs that configuration instead (make_config's options
over NB · WLAN · SPL 25, e.g. ``'{"network": "radio"}'``: the radio's cost beside the
same IR-SIM runs).

Run: ``.venv/bin/python benchmarks/bench_irsim.py [--repeats 3] [--sim-time 30]
[--options JSON]``
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import venv
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_scale import SCENARIOS, label_of, run_case

IRSIM_VERSION = "2.12.0"
VENV = Path(__file__).resolve().parent / ".irsim-venv"
TEAMS = {"s1": 3, "s2": 10, "s3": 30, "s4": 100}

#: Runs in IR-SIM's virtualenv: build the world, step it, report wall and CPU time.
IRSIM_CHILD = """
import json, sys, tempfile, time, os
import irsim
n, steps, behaviour = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3]
side = max(10.0, (n * 25.0) ** 0.5)
world = f'''
world: {{height: {side}, width: {side}, step_time: 0.1, sample_time: 0.1,
         collision_mode: stop, control_mode: auto}}
robot:
  - number: {n}
    distribution: {{name: random, range_low: [0.5, 0.5, -3.14],
                    range_high: [{side - 0.5}, {side - 0.5}, 3.14]}}
    kinematics: {{name: diff}}
    shape: {{name: circle, radius: 0.18}}
    behavior: {{name: {behaviour}}}
    vel_min: [-0.5, -1.0]
    vel_max: [0.5, 1.0]
'''
with tempfile.TemporaryDirectory() as tmp:
    path = os.path.join(tmp, "world.yaml")
    open(path, "w").write(world)
    env = irsim.make(path, display=False, disable_all_plot=True, headless=True, seed=1,
                     log_level="ERROR")
    wall0, cpu0 = time.perf_counter(), time.process_time()
    for _ in range(steps):
        env.step()
    wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
robots = env.robot_list
print(json.dumps({"wall": wall, "cpu": cpu, "sim": steps * 0.1,
                  "arrived": sum(bool(getattr(r, "arrive", False)) for r in robots),
                  "collided": sum(bool(getattr(r, "collision", False)) for r in robots)}))
"""


def irsim_python() -> Path:
    """IR-SIM's interpreter, its virtualenv made (and IR-SIM installed) on first use."""
    python = VENV / "bin" / "python"
    if not python.exists():
        venv.create(VENV, with_pip=True)
        subprocess.run(
            [str(python), "-m", "pip", "install", "--quiet", f"ir-sim=={IRSIM_VERSION}"],
            check=True,
        )
    return python


def run_irsim(n: int, sim_time: float, behaviour: str) -> dict[str, float]:
    steps = round(sim_time / 0.1)
    command = [str(irsim_python()), "-c", IRSIM_CHILD, str(n), str(steps), behaviour]
    if sys.platform.startswith("linux"):
        command = ["taskset", "-c", "0", *command]
    env = {**os.environ, "MPLBACKEND": "Agg"}
    done = subprocess.run(command, capture_output=True, text=True, check=True, env=env)
    return dict(json.loads(done.stdout.strip().splitlines()[-1]))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--sim-time", type=float, default=30.0)
    parser.add_argument("--options", type=json.loads, default={}, help="make_config options")
    args = parser.parse_args()
    irsim_python()
    print(f"{os.cpu_count()} CPUs, pinned to one core; {args.sim_time:g} s simulated; "
          f"MRComm {label_of(args.options)}; "
          f"load {os.getloadavg()}")  # fmt: skip
    cases = [(name, kind) for name in TEAMS for kind in ("mrcomm", "rvo", "dash")]
    runs: dict[tuple[str, str], list[dict[str, float]]] = {case: [] for case in cases}
    for _ in range(args.repeats):
        for name, kind in cases:  # interleaved: background load falls on every case alike
            if kind == "mrcomm":
                runs[(name, kind)].append(
                    run_case(SCENARIOS[name][1], args.sim_time, options=args.options)
                )
            else:
                runs[(name, kind)].append(run_irsim(TEAMS[name], args.sim_time, kind))
    print(f"load after: {os.getloadavg()}")
    print(
        "| robots | MRComm | IR-SIM rvo | IR-SIM dash | "
        "MRComm / rvo | MRComm / dash | rvo arrived, collided | dash arrived, collided |"
    )
    print("|---|---|---|---|---|---|---|---|")  # fmt: skip
    for name, n in TEAMS.items():
        rtf = {
            kind: statistics.median(r["sim"] / r["wall"] for r in runs[(name, kind)])
            for kind in ("mrcomm", "rvo", "dash")
        }
        last = {kind: runs[(name, kind)][-1] for kind in ("rvo", "dash")}
        print(
            f"| {n} | {rtf['mrcomm']:.3g}x | {rtf['rvo']:.3g}x | {rtf['dash']:.3g}x | "
            f"{rtf['mrcomm'] / rtf['rvo']:.2f} | {rtf['mrcomm'] / rtf['dash']:.2f} | "
            f"{last['rvo']['arrived']:.0f}, {last['rvo']['collided']:.0f} | "
            f"{last['dash']['arrived']:.0f}, {last['dash']['collided']:.0f} |"
        )


if __name__ == "__main__":
    main()
