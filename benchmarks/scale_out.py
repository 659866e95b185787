"""Speed-up of the Ray backend over the serial one, and Ray's overhead per task
(the figures of docs/SCALE_OUT.md).

For each number of Ray CPUs (a local instance started with that many), it times:

- an empty task, mapped 200 times on warm workers: Ray's own cost per task;
- ``pednav evaluate``'s work: 4 policies × 32 FootZupt episodes in batches of 8
  (16 tasks);
- ``pednav tune``'s work: 2 CMA-ES generations of 8 candidates × 8 episodes;
- ``pednav train --seeds``'s work: 2 PPO runs on WaistStep (6 updates of 16 × 64 steps);

each once on fresh workers (cold: process start, imports, compiled-kernel cache
loads) and once more on the same workers (warm), beside the serial backend, and
checks that every backend gives the serial result.

    .venv/bin/python benchmarks/scale_out.py [--cpus 1 2] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from agents.backends import RayBackend, SerialBackend
from agents.evaluate import evaluate
from agents.train import train_seeds
from baselines.tuned import search

FOOT = "pednav/FootZupt-v0"
WAIST = "pednav/WaistStep-v0"
TRAIN_HP = {"n_steps": 64, "batch_size": 256, "n_epochs": 5, "checkpoint_steps": 10**9}


def _noop(x: int) -> int:
    return x


def job_evaluate(backend: Any) -> Any:
    policies = ["paper", "tuned", "adaptive", "pretrained"]
    return evaluate(FOOT, policies, 32, 5000, backend=backend, lanes=8)


def job_tune(backend: Any) -> Any:
    out = search(
        FOOT, 4, episodes=8, generations=2, popsize=8, map_fn=backend.map, n_tasks=backend.workers
    )
    out.pop("seconds")
    return out


def job_train(backend: Any) -> Any:
    import hashlib

    from stable_baselines3 import PPO

    with tempfile.TemporaryDirectory() as tmp:
        dirs = train_seeds(
            WAIST,
            "ppo",
            [0, 1],
            tmp,
            backend=None if backend.name == "serial" else backend,
            timesteps=16 * 64 * 6,
            n_envs=16,
            hyperparams=TRAIN_HP,
        )
        digests = []
        for d in dirs:
            params = PPO.load(Path(d) / "model.zip", device="cpu").policy.state_dict()
            blob = b"".join(v.numpy().tobytes() for v in params.values())
            digests.append(hashlib.sha256(blob).hexdigest()[:16])
        return digests


JOBS: dict[str, Callable[[Any], Any]] = {
    "evaluate (16 tasks)": job_evaluate,
    "tune (2 generations)": job_tune,
    "train --seeds (2 runs)": job_train,
}


def timed(fn: Callable[[], Any]) -> tuple[float, Any]:
    start = time.perf_counter()
    out = fn()
    return time.perf_counter() - start, out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cpus", type=int, nargs="+", default=[1, 2], help="Ray CPU counts")
    ap.add_argument("--json", type=Path, default=None, help="also write the figures here")
    args = ap.parse_args()
    import ray

    rows: list[dict[str, Any]] = []
    serial = SerialBackend()
    reference = {}
    for name, job in JOBS.items():
        seconds, reference[name] = timed(lambda job=job: job(serial))
        rows.append({"job": name, "backend": "serial", "cold_s": seconds, "warm_s": seconds})
        print(f"serial  {name:<24} {seconds:7.1f} s", flush=True)
    overhead = {}
    for cpus in args.cpus:
        start_s, backend = timed(lambda cpus=cpus: RayBackend(num_cpus=cpus))
        backend.map(_noop, list(range(4 * cpus)))  # start the workers
        per_task, _ = timed(lambda backend=backend: backend.map(_noop, list(range(200))))
        overhead[cpus] = {"ray_start_s": start_s, "empty_task_ms": 1000 * per_task / 200}
        print(f"ray {cpus} CPU: start {start_s:.1f} s, empty task {1000 * per_task / 200:.2f} ms")
        for name, job in JOBS.items():
            cold, out = timed(lambda job=job, backend=backend: job(backend))
            warm, again = timed(lambda job=job, backend=backend: job(backend))
            same = out == reference[name] and again == reference[name]
            rows.append(
                {
                    "job": name,
                    "backend": f"ray {cpus} CPU",
                    "cold_s": cold,
                    "warm_s": warm,
                    "identical": same,
                }
            )
            print(
                f"ray {cpus}   {name:<24} cold {cold:7.1f} s, warm {warm:7.1f} s, "
                f"identical to serial: {same}",
                flush=True,
            )
        ray.shutdown()
    load = os.getloadavg()
    result = {
        "machine_cpus": os.cpu_count(),
        "load_average_at_end": load,
        "overhead": overhead,
        "rows": rows,
    }
    print(f"load average at the end: {load[0]:.1f} {load[1]:.1f} {load[2]:.1f}")
    if args.json:
        args.json.write_text(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
