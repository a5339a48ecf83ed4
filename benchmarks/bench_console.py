"""What the operator console costs at "as fast as possible": the same mission (S2, 10
robots, AH · NB · SPL 25, seed 1, run to its 900 s limit: its lost statuses keep a
console's mission open) simulated

* plainly (the mission stepped to the limit, no console);
* under a :class:`~mrcomm.console.session.ConsoleSession` at max speed, no page;
* by ``mrcomm run --console --speed inf`` with the page served and a headless Chromium
  showing it (its 4 Hz refreshes) — the whole console.

Prints simulated time / wall time (× real time) of each, CPU time where measured in
this process, and ``uptime`` before and after.

    PYTHONPATH=src .venv/bin/python benchmarks/bench_console.py
"""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

from mrcomm.console.session import ConsoleSession
from mrcomm.run.config import make_config
from mrcomm.run.operator_plan import OperatorPlan
from mrcomm.run.resources import ScenarioResources
from mrcomm.sim.mission import Mission

ROOT = Path(__file__).resolve().parents[1]
SCENARIO = ROOT / "data" / "scenarios" / "s2" / "s2.yaml"
OPTIONS = {"network": "ah", "behaviour": "nb", "spl": 25, "seed": 1, "max_time": 900}


def uptime() -> str:
    return subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()


def plain(resources: ScenarioResources) -> tuple[float, float, float]:
    mission = Mission(make_config(None, scenario=SCENARIO, **OPTIONS), resources, OperatorPlan())
    wall, cpu = time.perf_counter(), time.process_time()
    while mission.now < mission.config.max_time - 1e-9:
        mission.step()
    return mission.now, time.perf_counter() - wall, time.process_time() - cpu


def session_only(resources: ScenarioResources) -> tuple[float, float, float]:
    config = make_config(None, scenario=SCENARIO, **OPTIONS)
    session = ConsoleSession(config, resources, None, speed=float("inf"))
    cpu = time.process_time()
    result = session.run()
    return result.sim_time_s, result.wall_time_s, time.process_time() - cpu


def with_page() -> tuple[float, float]:
    from selenium import webdriver
    from selenium.webdriver.common.by import By

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    args = [sys.executable, "-c", "from mrcomm.cli.main import app; app()", "run", str(SCENARIO),
            "--console", "--port", str(port), "--speed", "inf", "--json",
            *(f"--{k.replace('_', '-')}={v}" for k, v in OPTIONS.items())]  # fmt: skip
    proc = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
                            env={**os.environ, "PYTHONPATH": str(ROOT / "src")})  # fmt: skip
    options = webdriver.ChromeOptions()
    options.binary_location = "/usr/bin/chromium"
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu"):
        options.add_argument(arg)
    driver = webdriver.Chrome(service=webdriver.ChromeService("/usr/bin/chromedriver"),
                              options=options)  # fmt: skip

    def watch() -> None:  # keep the page open and showing while the run lasts
        while proc.poll() is None:
            try:
                driver.get(f"http://127.0.0.1:{port}/")
                if driver.find_elements(By.ID, "clock"):
                    proc.wait()
                    return
            except Exception:
                pass
            time.sleep(0.05)

    watcher = threading.Thread(target=watch)
    watcher.start()
    out, _ = proc.communicate()
    watcher.join()
    driver.quit()
    result = json.loads(out)
    return result["sim_time_s"], result["wall_time_s"]


def main() -> None:
    resources = ScenarioResources.load(SCENARIO)
    print("before:", uptime())
    rows = []
    for _ in range(2):  # interleaved
        sim, wall, cpu = plain(resources)
        rows.append(("plain", sim, wall, cpu))
        sim, wall, cpu = session_only(resources)
        rows.append(("console session, no page", sim, wall, cpu))
        sim, wall = with_page()
        rows.append(("console with page + browser", sim, wall, float("nan")))
    print("after: ", uptime())
    for name, sim, wall, cpu in rows:
        print(f"{name:28s} {sim:7.1f} s simulated in {wall:6.2f} s wall ({sim / wall:5.0f}x), "
              f"CPU {cpu:6.2f} s")  # fmt: skip


if __name__ == "__main__":
    main()
