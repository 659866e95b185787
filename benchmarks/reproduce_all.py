"""Every paper reproduction at full size, with wall times (figures for docs/REPRODUCTION.md)."""

import time

from pednav_env import reproduce

if __name__ == "__main__":
    for paper in sorted(reproduce.PAPERS):
        t0 = time.perf_counter()
        result = reproduce.run(paper)
        print(result.format_table())
        print(f"wall time {time.perf_counter() - t0:.1f} s\n")
