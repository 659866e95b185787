"""The gait-rule's spread over independent CMA-ES searches (docs/RESULTS.md,
"Spread over search seeds").

    PYTHONPATH=. .venv/bin/python benchmarks/gait_rule_seeds.py average S1.json … --out DIR
    PYTHONPATH=. .venv/bin/python benchmarks/gait_rule_seeds.py insample S1.json …
    PYTHONPATH=. .venv/bin/python benchmarks/gait_rule_seeds.py table S1.json … \\
        [--shipped agents/pretrained/gait_rule.json] [--dev DEV.json] [--markdown]

Each ``S.json`` is a search's ``gait_rule.json`` (``python -m agents.gait_rule_search
… --seed k --episode-set k``) with its ``reevaluation``: the rule and the ``tuned``
constant on the same fresh training episodes (seeds from
:data:`pednav_env.seeds.REEVALUATION_SEED`) for every search.

``average`` writes ``DIR/gait_rule.json``: the rule with c averaged component-wise
over the searches, re-evaluated on the same training episodes (the searches'
``tuned`` errors are checked to be identical and reused).

``insample`` replays each search's rule and the ``tuned`` constant on the search's
own training episodes (its ``episode_set``; set 0 when the record has none, as the
shipped one): the objective against the constant it started from, in sample.

``table`` prints per search its parameters, its objective, its re-evaluation against
``tuned`` and against the shipped rule (paired t-test), and, from ``--dev`` (the
output of ``pednav evaluate pednav/FootZupt-v0 --policy tuned gait-rule S1.json …
--json``, policies named by the paths given; ``gait-rule`` there is ``--shipped``),
its development mean, divergence and paired difference against ``tuned`` (— for the
shipped rule when the evaluation has no ``gait-rule``); then the mean ± sd over the
searches (files whose record has ``averaged_from`` are shown but not counted) and
the selection rule of docs/RESULTS.md applied to the re-evaluations only: the lowest
re-evaluated mean replaces the shipped rule only if it beats it there at paired
p < 0.05. Nothing is replayed by ``table``.
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
from oracle_gap import paired  # benchmarks/oracle_gap.py (the script directory is on sys.path)

from agents.gait_rule import PARAMS_FILE, read_params, write_params
from agents.gait_rule_search import OUT_NAME, rule_errors, tuned_start
from pednav_env.seeds import REEVALUATION_SEED, search_seeds

#: The selection rule's threshold (paired t-test on the re-evaluation episodes).
SELECT_P = 0.05


def load(path: str | Path) -> dict[str, Any]:
    """A search's record with its re-evaluation; ValueError naming the file."""
    path = Path(path)
    read_params(path)  # checks the rule's keys
    data = json.loads(path.read_text())
    r = data.get("reevaluation")
    if not isinstance(r, dict) or "episode_errors_m" not in r or "tuned_episode_errors_m" not in r:
        raise ValueError(
            f"{path}: no 'reevaluation' with per-episode errors (run with --reevaluate)"
        )
    data["path"] = str(path)
    data["rule_err"] = np.asarray(r["episode_errors_m"], dtype=float)
    data["tuned_err"] = np.asarray(r["tuned_episode_errors_m"], dtype=float)
    return data


def check_same_episodes(runs: list[dict[str, Any]]) -> None:
    """All re-evaluations on the same episodes, with the same ``tuned`` errors."""
    first = runs[0]
    for r in runs[1:]:
        if r["reevaluation"]["episode_seeds"] != first["reevaluation"]["episode_seeds"]:
            raise ValueError(f"{r['path']}: re-evaluated on other episodes than {first['path']}")
        if not np.array_equal(r["tuned_err"], first["tuned_err"]):
            raise ValueError(f"{r['path']}: its tuned errors differ from {first['path']}'s")


def average(paths: list[str], out: Path) -> Path:
    runs = [load(p) for p in paths]
    check_same_episodes(runs)
    c = np.mean([r["c"] for r in runs], axis=0)
    first = runs[0]
    n = first["reevaluation"]["episodes"]
    seeds = [REEVALUATION_SEED + i for i in range(n)]
    if [seeds[0], seeds[-1]] != first["reevaluation"]["episode_seeds"]:
        raise ValueError(f"{first['path']}: re-evaluation seeds are not {seeds[0]}…{seeds[-1]}")
    params = replace(read_params(first["path"]), c=tuple(float(v) for v in c))
    err = rule_errors(c[None], seeds, params)[0]
    record = {
        "averaged_from": [r["path"] for r in runs],
        "reevaluation": {
            "episodes": n,
            "episode_seeds": [seeds[0], seeds[-1]],
            "mean_m": float(err.mean()),
            "tuned_mean_m": float(first["tuned_err"].mean()),
            "episode_errors_m": err.round(4).tolist(),
            "tuned_episode_errors_m": first["tuned_err"].tolist(),
        },
    }
    return write_params(params, out / OUT_NAME, record)


def insample(paths: list[str]) -> None:
    print("search  episodes  objective (m)  replayed (m)  tuned (m)  Δ in sample (m)")
    for path in paths:
        data = load(path)
        params = read_params(path)
        seeds = search_seeds(int(data.get("episode_set", 0)), int(data["episodes"]))
        err = rule_errors(np.stack([np.asarray(params.c), tuned_start()]), seeds, params)
        print(
            f"{'/'.join(Path(path).parts[-2:])}  {seeds[0]}…{seeds[-1]}  "
            f"{data['objective_m']:.3f}  {err[0].mean():.3f}  {err[1].mean():.3f}  "
            f"{err[0].mean() - err[1].mean():+.3f}"
        )


def dev_rows(dev: dict[str, Any], shipped: str) -> dict[str, dict[str, Any]]:
    """The dev evaluation's policies by resolved path (``gait-rule``: ``shipped``)."""
    out = {}
    for p in dev["policies"]:
        key = shipped if p["name"] == "gait-rule" else p["name"]
        out[str(Path(key).resolve()) if key != "tuned" else "tuned"] = p
    return out


def table(paths: list[str], shipped: str, dev_path: str | None, markdown: bool) -> None:
    ship = load(shipped)
    runs = [load(p) for p in paths]
    check_same_episodes([ship, *runs])
    dev = json.loads(Path(dev_path).read_text()) if dev_path else None
    rows_dev = dev_rows(dev, shipped) if dev else {}
    if dev and "tuned" not in rows_dev:
        raise ValueError(f"{dev_path}: no policy named tuned")
    tuned_dev = np.asarray(rows_dev["tuned"]["episode_errors"]) if dev else None
    if dev:
        print(
            f"dev: {dev['episodes']} episodes from seed {dev['seed']}; "
            f"tuned {tuned_dev.mean():.3f} m"
        )
    n = len(ship["rule_err"])
    print(f"re-evaluation: {n} training episodes; tuned {ship['tuned_err'].mean():.3f} m")
    head = [
        "search",
        "c",
        "objective (m)",
        "re-eval (m)",
        "Δ vs tuned",
        "p",
        "Δ vs shipped",
        "p",
    ]
    if dev:
        head += ["dev (m)", "diverged", "Δ vs tuned", "p t", "p W", "better"]
    sep = " | " if markdown else "  "
    if markdown:
        print("| " + " | ".join(head) + " |")
        print("|" + "---|" * len(head))
    else:
        print(sep.join(head))
    gains_re, gains_dev, p_dev = [], [], []
    for r in [ship, *runs]:
        d_t, p_t, _ = paired(r["rule_err"], r["tuned_err"])
        d_s, p_s, _ = paired(r["rule_err"], ship["rule_err"])
        name = "shipped" if r is ship else "/".join(Path(r["path"]).parts[-2:])
        row = [
            name,
            "(" + ", ".join(f"{v:.3f}" for v in r["c"]) + ")",
            f"{r['objective_m']:.2f}" if "objective_m" in r else "—",
            f"{r['rule_err'].mean():.3f}",
            f"{d_t:+.3f}",
            f"{p_t:.2g}",
            "—" if r is ship else f"{d_s:+.3f}",
            "—" if r is ship else f"{p_s:.2g}",
        ]
        counted = r is not ship and "averaged_from" not in r
        if counted:
            gains_re.append(d_t)
        key = str(Path(r["path"]).resolve())
        if dev and key not in rows_dev:
            if r is not ship:
                raise ValueError(f"{dev_path}: no policy named {r['path']}")
            row += ["—"] * 6  # the shipped rule was not played (no gait-rule policy)
        elif dev:
            e = np.asarray(rows_dev[key]["episode_errors"])
            dd, pd, pw = paired(e, tuned_dev)
            row += [
                f"{e.mean():.3f}",
                f"{100 * rows_dev[key]['divergence_rate']:.1f} %",
                f"{dd:+.3f}",
                f"{pd:.2g}",
                f"{pw:.2g}",
                f"{100 * np.mean(e < tuned_dev):.0f} %",
            ]
            if counted:
                gains_dev.append(dd)
                p_dev.append((dd, pd))
        print(("| " + sep.join(row) + " |") if markdown else sep.join(row))
    if len(gains_re) > 1:
        g = np.array(gains_re)
        print(
            f"over {len(g)} searches: re-evaluated Δ vs tuned {g.mean():+.3f} "
            f"± {g.std(ddof=1):.3f} m (mean ± sd), range [{g.min():+.3f}, {g.max():+.3f}]"
        )
    if len(gains_dev) > 1:
        g = np.array(gains_dev)
        wins = sum(1 for d, p in p_dev if d < 0 and p < 0.01)
        print(
            f"over {len(g)} searches: dev Δ vs tuned {g.mean():+.3f} ± {g.std(ddof=1):.3f} m "
            f"(mean ± sd), range [{g.min():+.3f}, {g.max():+.3f}]; "
            f"{wins} of {len(g)} beat tuned at p < 0.01"
        )
    best = min(runs, key=lambda r: r["rule_err"].mean())
    d, p, _ = paired(best["rule_err"], ship["rule_err"])
    if best["rule_err"].mean() < ship["rule_err"].mean() and p < SELECT_P:
        verdict = f"replace the shipped rule by {best['path']} (Δ {d:+.3f} m, p = {p:.2g})"
    else:
        verdict = (
            f"keep the shipped rule (lowest re-evaluated candidate {best['path']}: "
            f"{best['rule_err'].mean():.3f} m against {ship['rule_err'].mean():.3f} m, "
            f"Δ {d:+.3f} m, p = {p:.2g})"
        )
    print("selection (re-evaluation only): " + verdict)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    a = sub.add_parser("average", help="the rule with c averaged over the searches")
    a.add_argument("searches", nargs="+")
    a.add_argument("--out", required=True, type=Path)
    i = sub.add_parser("insample", help="each search's rule and tuned on its own episodes")
    i.add_argument("searches", nargs="+")
    t = sub.add_parser("table", help="the searches side by side")
    t.add_argument("searches", nargs="+")
    t.add_argument("--shipped", default=str(PARAMS_FILE))
    t.add_argument("--dev", help="pednav evaluate --json output with every rule and tuned")
    t.add_argument("--markdown", action="store_true")
    args = ap.parse_args(argv)
    try:
        if args.cmd == "average":
            print(f"wrote {average(args.searches, args.out)}")
        elif args.cmd == "insample":
            insample(args.searches)
        else:
            table(args.searches, args.shipped, args.dev, args.markdown)
    except (OSError, ValueError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
