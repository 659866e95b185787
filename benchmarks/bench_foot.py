"""Throughput of pednav/FootZupt-v0: ``pednav bench foot`` with its table and JSON."""

import json
import sys

from agents.bench import bench_foot, format_table

if __name__ == "__main__":
    result = bench_foot()
    print(format_table(result))
    json.dump(result, sys.stdout)
    print()
