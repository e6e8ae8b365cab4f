"""How long ``GET /jobs/{id}/outline.png`` takes to draw (``interactive.outline_png``):
every species' tree (seed 3, result yaw 30) from three turns, at 256 and 512 px; the
median of the three per species, then the median and the worst over the species.

    PYTHONPATH=$PWD .venv/bin/python benchmarks/probes/outline_time.py
"""

from __future__ import annotations

import statistics
import time

from treesketch.service.interactive import outline_png
from weberpenn import species


def main() -> None:
    palm = {"params": species.sample("palm", 0).to_dict(), "species": "palm", "yaw": 0.0}
    outline_png(palm, 0.0, 64)  # the imports, once
    for size in (256, 512):
        per = {}
        for name in species.SPECIES:
            summary = {"params": species.sample(name, 3).to_dict(), "species": name, "yaw": 30.0}
            times = []
            for turn in (0.0, 60.0, -90.0):
                t = time.perf_counter()
                outline_png(summary, turn, size)
                times.append(time.perf_counter() - t)
            per[name] = statistics.median(times)
        worst = max(per, key=lambda k: per[k])
        each = ", ".join(f"{k} {v:.3f}" for k, v in per.items())
        print(
            f"size {size}: median over species {statistics.median(per.values()):.3f} s, "
            f"max {per[worst]:.3f} s ({worst}); {each}"
        )


if __name__ == "__main__":
    main()
