"""Behaviour fingerprint: hashes of every env's trajectories and every paper reproduction.

Used to show that a refactor changes no behaviour: run it before and after and compare
the two JSON files (``--out``). Each entry is a SHA-256 of the raw bytes of what the code
produced (observations, rewards, termination flags, info arrays; reproduction JSON), so
equal hashes mean bit-identical outputs.

    .venv/bin/python benchmarks/fingerprint.py --out /tmp/before.json
    # ... change code ...
    .venv/bin/python benchmarks/fingerprint.py --out /tmp/after.json --compare /tmp/before.json
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np

import pednav_env  # noqa: F401  (registers the envs)

REPLAY_DATA = Path(__file__).resolve().parents[1] / "tests" / "data"


def _h(*arrays) -> str:
    d = hashlib.sha256()
    for a in arrays:
        d.update(np.ascontiguousarray(np.asarray(a, dtype=np.float64)).tobytes())
    return d.hexdigest()[:16]


def _info_hash(info: dict) -> str:
    d = hashlib.sha256()
    for k in sorted(info):
        v = info[k]
        # "context" (privileged truth about the coming interval) is left out so
        # that the figures compare with those made before it existed
        if k.startswith("_") or k in ("final_obs", "final_info", "knobs", "context"):
            continue
        try:
            arr = np.asarray(v, dtype=np.float64)
        except (TypeError, ValueError):
            d.update(repr(v).encode())
            continue
        d.update(k.encode())
        d.update(np.ascontiguousarray(arr).tobytes())
    if "knobs" in info:
        d.update(json.dumps(info["knobs"], sort_keys=True, default=float).encode())
    return d.hexdigest()[:16]


def scalar_env(env_id: str, seeds: range, steps: int, kwargs: dict) -> dict:
    out = {}
    env = gym.make(env_id, **kwargs).unwrapped
    for seed in seeds:
        rng = np.random.default_rng(seed + 77)
        obs, info = env.reset(seed=seed)
        parts = [_h(obs), _info_hash(info)]
        for _ in range(steps):
            a = rng.uniform(-1, 1, env.action_space.shape).astype(np.float32)
            obs, r, term, trunc, info = env.step(a)
            parts += [_h(obs, [r, term, trunc]), _info_hash(info)]
            if term or trunc:
                obs, info = env.reset()
                parts += [_h(obs), _info_hash(info)]
        out[f"{env_id} scalar seed {seed} {kwargs}"] = hashlib.sha256(
            "".join(parts).encode()
        ).hexdigest()[:16]
    return out


def vector_env(env_id: str, n: int, steps: int, kwargs: dict) -> dict:
    env = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point", **kwargs)
    env = env.unwrapped if hasattr(env, "unwrapped") else env
    rng = np.random.default_rng(5)
    obs, info = env.reset(seed=123)
    parts = [_h(obs), _info_hash(info)]
    for _ in range(steps):
        a = rng.uniform(-1, 1, env.action_space.shape).astype(np.float32)
        obs, r, term, trunc, info = env.step(a)
        parts += [_h(obs, r, term, trunc), _info_hash(info)]
    return {f"{env_id} vector n={n}": hashlib.sha256("".join(parts).encode()).hexdigest()[:16]}


def reproductions() -> dict:
    from pednav_env import reproduce

    out = {}
    for paper in sorted(reproduce.PAPERS):
        result = reproduce.run(paper)
        d = result.to_json_dict()
        d.pop("seconds")  # wall time
        text = json.dumps(d, sort_keys=True)  # notes carry wall times
        out[f"reproduce {paper}"] = hashlib.sha256(text.encode()).hexdigest()[:16]
    return out


def evaluations() -> dict:
    from agents.evaluate import evaluate

    out = {}
    for env_id in ("pednav/FootZupt-v0", "pednav/WaistStep-v0", "pednav/MarkerTrack-v0"):
        # the foot env's paper filter family explicitly (the learned policies'
        # default family is shoe); the per-policy "filter" and "divergence_ci95"
        # entries are left out so that the figures compare with those made before
        # they existed (the interval is a function of the divergence flags)
        kwargs = {"filter": "paper"} if env_id == "pednav/FootZupt-v0" else {}
        res = evaluate(env_id, ["paper", "tuned", "adaptive", "pretrained"], 6, 4242, kwargs, None)
        drop = ("filter", "divergence_ci95")
        text = json.dumps(_strip_times(res, drop=drop), sort_keys=True, default=str)
        out[f"evaluate {env_id}"] = hashlib.sha256(text.encode()).hexdigest()[:16]
    return out


def _strip_times(obj, drop: tuple[str, ...] = ()):
    if isinstance(obj, dict):
        return {
            k: _strip_times(v, drop)
            for k, v in obj.items()
            if "second" not in k and "time" not in k and k not in drop
        }
    if isinstance(obj, list):
        return [_strip_times(v, drop) for v in obj]
    return obj


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--compare", type=Path)
    ap.add_argument("--no-reproduce", action="store_true")
    args = ap.parse_args()
    result: dict[str, str] = {}
    sims = ["pednav/FootZupt-v0", "pednav/WaistStep-v0", "pednav/MarkerTrack-v0"]
    for env_id in sims:
        result |= scalar_env(env_id, range(3), 60, {})
        result |= vector_env(env_id, 4, 60, {})
    for env_id in sims:
        for scen in ("paper", "random"):
            try:
                result |= scalar_env(env_id, range(100, 102), 40, {"scenario": scen})
            except Exception as exc:  # a scenario name an env does not have
                result[f"{env_id} {scen}"] = f"error {type(exc).__name__}"
    # the shoe filter family (SHOE detector, a ZUPT at every stance sample)
    result |= scalar_env("pednav/FootZupt-v0", range(200, 202), 40, {"filter": "shoe"})
    result |= scalar_env(
        "pednav/FootZupt-v0", range(202, 204), 40, {"filter": "shoe", "scenario": "random"}
    )
    result |= {
        f"{k} shoe": v
        for k, v in vector_env(
            "pednav/FootZupt-v0", 4, 40, {"filter": "shoe", "scenario": "random"}
        ).items()
    }
    replay_kwargs = {
        "data_dir": str(
            Path(__file__).resolve().parents[2] / "shared" / "data" / "pyshoe-vicon-dev"
        )
    }
    try:
        result |= scalar_env("pednav/FootZuptReplay-v0", range(2), 40, replay_kwargs)
        result |= scalar_env(
            "pednav/FootZuptReplay-v0", range(2), 40, replay_kwargs | {"filter": "shoe"}
        )
    except Exception as exc:
        result["replay"] = f"error {type(exc).__name__}: {exc}"[:200]
    result |= evaluations()
    if not args.no_reproduce:
        result |= reproductions()
    args.out.write_text(json.dumps(result, indent=1, sort_keys=True))
    print(json.dumps(result, indent=1, sort_keys=True))
    if args.compare:
        ref = json.loads(args.compare.read_text())
        diff = [k for k in sorted(set(ref) | set(result)) if ref.get(k) != result.get(k)]
        for k in diff:
            print(f"DIFFERS: {k}: {ref.get(k)} -> {result.get(k)}")
        print("IDENTICAL" if not diff else f"{len(diff)} DIFFER")
        return 1 if diff else 0
    return 0


if __name__ == "__main__":
    sys.exit(main())
