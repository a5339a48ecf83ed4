"""Derive the bundled radio validation sets (``data/radio/validation/``) from the public
Wi-Fi RSS/RTT dataset for model selection (GitHub
``Fx386483710/WiFi_RSS_RTT_Dataset_for_Model_Selection``, MIT licence): three indoor
floors (a lecture theatre, an office, a corridor), access points at known positions,
60 scans at each reference point of a 0.6 m grid, a line-of-sight label per access
point and reference point, and a train/test split whose points do not overlap.

Each derived row is one (reference point, access point) pair: the access point is the
transmitter, the reference point the receiver, ``rssi`` the mean of the scans that heard
it (the dataset's -200 dBm means "not heard": left out), ``walls`` 0 when the dataset
labels the access point in line of sight of the point and 1 otherwise (the dataset has
no floor plan, so the obstruction is one class, not a wall count), ``scans`` and
``rssi_sd`` how many scans heard it and their spread. Averaging the scans removes fast
fading: what is left is the mean power plus shadowing, what a radio profile predicts.

    .venv/bin/python scripts/make_wifi_validation_set.py DATASET_DIR [--out data/radio/validation]

DATASET_DIR holds the dataset's ``data/`` files (a clone of the repository). Nothing is
downloaded.
"""

from __future__ import annotations

import argparse
import csv
import re
import shutil
from collections import defaultdict
from pathlib import Path

SOURCE = "https://github.com/Fx386483710/WiFi_RSS_RTT_Dataset_for_Model_Selection"
#: The dataset's floor names, its file names and ours.
FLOORS = {"lecture theatre": "lecture_theatre", "office": "office", "corridor": "corridor"}
NOT_HEARD = -200.0


def access_points(path: Path) -> dict[str, list[tuple[float, float]]]:
    """Floor -> access point positions (m), from the dataset's position file."""
    text = path.read_text(encoding="utf-8")
    out: dict[str, list[tuple[float, float]]] = {}
    for floor in FLOORS:
        block = text.split(floor, 1)[1]
        xs = re.search(r"AP X:\s*([-\d.,\s]+)", block)
        ys = re.search(r"AP Y:\s*([-\d.,\s]+?)(?:[A-Za-z]|$)", block)
        assert xs and ys, floor
        x = [float(v) for v in xs.group(1).split(",") if v.strip()]
        y = [float(v) for v in ys.group(1).split(",") if v.strip()]
        out[floor] = list(zip(x, y[: len(x)], strict=True))
    return out


def derive(source: Path, aps: list[tuple[float, float]]) -> list[dict[str, object]]:
    """One row per (reference point, access point) heard at least once."""
    scans: dict[tuple[float, float, int], list[float]] = defaultdict(list)
    los: dict[tuple[float, float], set[int]] = {}
    with source.open(newline="", encoding="utf-8") as handle:
        for row in csv.DictReader(handle):
            point = (float(row["X"]), float(row["Y"]))
            los[point] = {int(v) for v in row["LOS APs"].split()}
            for k in range(1, len(aps) + 1):
                value = float(row[f"AP{k} RSS(dBm)"])
                if value != NOT_HEARD:
                    scans[(*point, k)].append(value)
    rows = []
    for (x, y, k), values in sorted(scans.items()):
        mean = sum(values) / len(values)
        sd = (sum((v - mean) ** 2 for v in values) / max(len(values) - 1, 1)) ** 0.5
        ax, ay = aps[k - 1]
        rows.append({"x_tx": ax, "y_tx": ay, "x_rx": x, "y_rx": y, "rssi": round(mean, 3),
                     "walls": 0 if k in los[(x, y)] else 1, "ap": k, "scans": len(values),
                     "rssi_sd": round(sd, 3)})  # fmt: skip
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dataset", type=Path)
    parser.add_argument("--out", type=Path, default=Path("data/radio/validation"))
    args = parser.parse_args()
    positions = access_points(args.dataset / "lecture theatre+office+corridor_AP_position.txt")
    for floor, stem in FLOORS.items():
        folder = args.out / f"wifi-{stem.replace('_', '-')}"
        folder.mkdir(parents=True, exist_ok=True)
        for split in ("train", "test"):
            source = args.dataset / f"database_{stem}_{split}.csv"
            rows = derive(source, positions[floor])
            with (folder / f"{split}.csv").open("w", newline="", encoding="utf-8") as handle:
                handle.write(
                    f"# {floor}, {split} split: derived by scripts/make_wifi_validation_set.py "
                    f"from {source.name} of {SOURCE} (MIT licence: see ../NOTICE.md).\n"
                    "# One row per (reference point, access point): the access point transmits; "
                    "rssi = mean of the scans that heard it (dBm); walls = 0 in line of sight "
                    "as the dataset labels it, 1 obstructed (a class, not a count).\n"
                )
                writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
                writer.writeheader()
                writer.writerows(rows)
            print(f"{folder / f'{split}.csv'}: {len(rows)} readings")
    shutil.copyfile(args.dataset / "LICENSE", args.out / "LICENSE-wifi-rss-rtt")


if __name__ == "__main__":
    main()
