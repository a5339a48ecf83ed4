"""Generate the bundled example RSSI trace for ESD replay in simulation.

SYNTHETIC: there is no public recording of the original robots' wireless cards, so the
trace is made by running scenario S1 (AH, SSD, LF, seed 1) in simulation, taking the
RSSI that the bundled SSD model predicts for every robot pair at 2 Hz (what a pulse
process would poll), and adding measurement noise (Gaussian, sigma 1.5 dB, seed 7) and
rounding to whole dBm, as `iw` reports. Replace it with a trace recorded by
`mrcomm pulse` on real robots for effective signal degradation.

    .venv/bin/python scripts/make_esd_trace.py [--out data/traces/s1_synthetic_esd.csv]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from mrcomm.net.signal.csvio import write_csv
from mrcomm.run.config import make_config
from mrcomm.sim.mission import run_mission

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--out", type=Path, default=ROOT / "data" / "traces" / "s1_synthetic_esd.csv"
    )
    args = parser.parse_args()
    config = make_config(
        None,
        scenario=ROOT / "data" / "scenarios" / "s1.yaml",
        network="ah",
        threshold="ssd",
        behaviour="lf",
        spl=0,
        seed=1,
    )
    result = run_mission(config)
    rng = np.random.default_rng(7)
    rows = [
        (f"{t:.1f}", src, dst, round(rssi + rng.normal(0.0, 1.5)))
        for t, src, dst, rssi in result.rssi_series
    ]
    write_csv(
        args.out,
        ("time", "from", "to", "rssi"),
        rows,
        comments=(
            "SYNTHETIC RSSI trace for ESD replay in simulation (not a measurement).",
            "Made by scripts/make_esd_trace.py: S1, AH, SSD, LF, seed 1; the bundled SSD",
            "model's RSSI per robot pair at 2 Hz + Gaussian noise (sigma 1.5 dB, seed 7),",
            "rounded to whole dBm.",
            "Columns: time (s), from (measuring robot), to (peer), rssi (dBm).",
        ),
    )
    print(f"wrote {args.out}: {len(rows)} readings over {result.sim_time_s:.1f} s")


if __name__ == "__main__":
    main()
