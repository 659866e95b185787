"""``pednav run``, ``pednav simulate`` and ``pednav sim2real``: the commands on recorded and
simulated foot walks (docs/REAL_DATA.md, docs/SIM_TO_REAL.md)."""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import replace
from typing import TYPE_CHECKING

from agents.cli_types import nonnegative_int, output_dir, positive_float, positive_int

if TYPE_CHECKING:
    from pednav_env.calibration.sim_model import SimModel
    from pednav_env.replay.simulate import SimulatorModel


def _cmd_run(args: argparse.Namespace) -> int:
    from pathlib import Path

    from agents.run_recording import RunOptions, format_folder, format_text, run, run_folder
    from pednav_env.io import CsvLayout, LoadOptions

    layout = None
    if args.layout is not None or args.rate is not None:
        layout = CsvLayout.from_json(args.layout) if args.layout is not None else CsvLayout()
        if args.rate is not None:
            layout = replace(layout, rate_hz=args.rate)
    options = RunOptions(
        fmt=args.format,
        policy=args.policy,
        mounting=args.mounting,
        load=LoadOptions(
            max_gap_s=args.max_gap,
            saturation=args.saturation,
            gyro_range=args.gyro_range,
            accel_range=args.accel_range,
            check_units=not args.no_unit_check,
        ),
        layout=layout,
        footprints=None if args.footprints == "none" else args.footprints,
    )
    if Path(args.recording).is_dir():
        plot_dir = None if args.plot is None else output_dir(args.plot, "--plot")
        out_dir = None if args.out is None else output_dir(args.out, "--out")
        result = run_folder(args.recording, options, plot_dir, out_dir)
        print(json.dumps(result) if args.json else format_folder(result))
        return 1 if any("error" in r for r in result["recordings"]) else 0
    summary, rec = run(args.recording, options, args.plot, args.out)
    if rec.issues:
        print(rec.summary(), file=sys.stderr)
    print(json.dumps(summary) if args.json else format_text(rec.name, summary))
    return 0


def _cmd_simulate(args: argparse.Namespace) -> int:
    from pednav_env.replay.simulate import (
        SimulateConfig,
        check_output_path,
        simulate_walk,
        write_recording_csv,
    )

    check_output_path(args.out)  # before the simulation
    config = SimulateConfig(
        model=_simulator_model(args.model),
        speed_mps=None if args.speed is None else tuple(args.speed),
        gait=args.gait,
        duration_s=args.duration,
        rate_hz=args.rate,
        imu_grade=args.imu,
        stops=args.stops,
        seed=args.seed,
    )
    walk = simulate_walk(config)
    path = write_recording_csv(walk, args.out)
    print(
        f"wrote {path}: {walk.time[-1]:.1f} s at {config.rate_hz:g} Hz, {walk.distance_m:.1f} m, "
        f"IMU {config.grade}, model {config.model.name}, seed {config.seed}"
    )
    return 0


def _sim_model(name: str) -> SimModel:
    """``--model``: a named model of ``pednav sim2real`` or a fitted-parameter JSON file."""
    from pathlib import Path

    from pednav_env.calibration.compare import MODELS, model_from_json

    if name in MODELS:
        return MODELS[name]
    if name.endswith(".json") or Path(name).exists():
        return model_from_json(name)
    raise ValueError(
        f"--model {name!r}: use one of {', '.join(MODELS)} or a fitted-parameter .json file"
    )


def _simulator_model(name: str) -> SimulatorModel:
    """``pednav simulate --model``: the default model unless another is named."""
    from pednav_env.replay.simulate import DEFAULT_MODEL, SimulatorModel

    if name == DEFAULT_MODEL.name:
        return DEFAULT_MODEL
    model = _sim_model(name)
    stance = model.stance
    return SimulatorModel(model.name, model.imu_grade, None if stance is None else lambda: stance)


def _cmd_sim2real(args: argparse.Namespace) -> int:
    from pathlib import Path

    from pednav_env.calibration.compare import compare
    from pednav_env.calibration.sources import distinct_walks, samples_from_recording
    from pednav_env.calibration.stats import walk_stats
    from pednav_env.io import find_recordings, load_recording

    model = _sim_model(args.model)
    if args.walks < 2:
        raise ValueError(f"--walks must be ≥ 2 (each band's spread), got {args.walks}")
    if args.nav_walks < 2:
        raise ValueError(f"--nav-walks must be ≥ 2 (a spread of twins), got {args.nav_walks}")
    nav_setup = None
    if args.nav:
        from pednav_env.replay.setup import SETUP_NAMES, load_setup, named_setup

        name = args.nav_setup
        try:
            nav_setup = named_setup(name) if name in SETUP_NAMES else load_setup(name)
        except ValueError as exc:
            raise ValueError(f"--nav-setup: {exc}") from None
    if args.plot is not None:
        output_dir(args.plot, "--plot")
    paths = []
    for item in args.recordings:
        p = Path(item)
        paths.extend(find_recordings(p) if p.is_dir() else [p])
    if not paths:
        raise ValueError(f"no recordings (.csv, .mat) in {' '.join(args.recordings)}")
    for p in paths:
        if not p.is_file():
            raise ValueError(f"{p}: no such file")
    recordings = [load_recording(p) for p in paths]
    samples = [samples_from_recording(r) for r in recordings]
    recording_of = {id(w): r for w, r in zip(samples, recordings, strict=True)}
    walks, dropped = distinct_walks(samples)
    for copy, kept in dropped:
        print(
            f"{copy}: the same walk as {kept} (footprints and duration); counted once",
            file=sys.stderr,
        )
    real = [walk_stats(w) for w in walks]
    report = compare(real, model, args.walks, args.seed)
    if args.plot is not None:
        from pednav_env.calibration.plots import write_figures

        for path in write_figures(report, args.plot):
            print(f"wrote {path}", file=sys.stderr)
    level = None
    if args.nav:
        from agents.error_level import error_level

        kept = [recording_of[id(w)] for w in walks]
        level = error_level(
            kept, model, args.nav_walks, args.seed, nav_setup, args.nav_setup, args.nav_twins
        )
        if args.plot is not None:
            from agents.error_level import write_figure

            figure = write_figure(level, args.plot)
            if figure is not None:
                print(f"wrote {figure}", file=sys.stderr)
    if args.json:
        out = report.to_json()
        if level is not None:
            out["error_level"] = level.to_json()
        print(json.dumps(out))
    else:
        print(report.format_text())
        if level is not None:
            print()
            print(level.format_text())
    return 0


def _add_sim2real(sub: argparse._SubParsersAction) -> None:
    s2r = sub.add_parser(
        "sim2real", help="the foot simulator beside recorded walks (docs/SIM_TO_REAL.md)"
    )
    s2r.add_argument("recordings", nargs="+", help=".mat/.csv recordings or directories of them")
    s2r.add_argument(
        "--model",
        default="calibrated",
        help="calibrated, today, or a fitted-parameter JSON file "
        "(e.g. benchmarks/results/calibrate_foot_v3.json; default calibrated)",
    )
    s2r.add_argument(
        "--walks",
        type=positive_int,
        default=60,
        help="simulated walks per speed band, ≥ 2 (default 60)",
    )
    s2r.add_argument("--seed", type=nonnegative_int, default=0, help="simulation seed (default 0)")
    s2r.add_argument(
        "--nav",
        action="store_true",
        help="also the error level: real-fixed's ARMSE on each recording with dense truth "
        "(footprint error with footprints) beside simulated twins that walk its strides "
        "(docs/SIM_TO_REAL.md)",
    )
    s2r.add_argument(
        "--nav-walks",
        type=positive_int,
        default=20,
        help="simulated twins per recording for --nav, ≥ 2 (default 20)",
    )
    s2r.add_argument(
        "--nav-twins",
        choices=("footfalls", "circles", "straight"),
        default="footfalls",
        help="how the --nav twins walk: each recording's own strides (default), circles of "
        "its turn per stride at its speed, or straight legs at its speed",
    )
    s2r.add_argument(
        "--nav-setup",
        metavar="NAME|FILE",
        default="real-fixed",
        help="the filter setup of --nav: real-fixed (default), paper, or a setup JSON file "
        "as `pednav run --policy` reads (docs/REAL_DATA.md)",
    )
    s2r.add_argument("--json", action="store_true", help="print one JSON object")
    s2r.add_argument("--plot", metavar="DIR", default=None, help="write histograms to DIR")
    s2r.set_defaults(func=_cmd_sim2real)


def add_recording_commands(sub: argparse._SubParsersAction) -> None:
    """Add the run, simulate and sim2real subcommands to ``sub``."""
    ru = sub.add_parser("run", help="run the ZUPT-UKF on a recording (docs/REAL_DATA.md)")
    ru.add_argument(
        "recording", help="a .csv or .mat recording, or a folder of them (a summary table)"
    )
    ru.add_argument(
        "--format",
        default="auto",
        help="auto (default: from the suffix and the content), csv, xio, sensorconnect, "
        "pyshoe or gcp-mat",
    )
    ru.add_argument(
        "--policy",
        default="real-fixed",
        help="real-fixed (default: the configuration chosen on real walks), twins "
        "(real-fixed with its SHOE threshold chosen for the recording on simulated twins of "
        "its own strides; about 5 s per recording), paper (paper "
        "003's filter; fails at walking speed on some sensors), a setup JSON file "
        "(docs/REAL_DATA.md), or a policy name/path as in `pednav evaluate`",
    )
    ru.add_argument(
        "--footprints",
        metavar="FILE|none",
        default="auto",
        help="footprint CSV (truth at footfalls), or none; default: the file's own, or "
        "<stem>_footprints.csv beside a SensorConnect CSV",
    )
    ru.add_argument("--mounting", default=None, help="auto (default), none or axes like x,-y,-z")
    lo = ru.add_argument_group("loading (docs/REAL_DATA.md, Loading)")
    lo.add_argument(
        "--layout",
        metavar="JSON|FILE",
        default=None,
        help='generic CSV column names and units, inline or in a file, e.g. \'{"time": "t", '
        '"gyro_unit": "deg/s", "accel_unit": "g"}\' (keys as in CsvLayout)',
    )
    lo.add_argument(
        "--rate",
        metavar="HZ",
        type=positive_float,
        default=None,
        help="sample rate of a generic CSV without a time column",
    )
    lo.add_argument(
        "--max-gap",
        metavar="S",
        type=positive_float,
        default=0.1,
        help="longest gap in the time column accepted, s (default 0.1)",
    )
    lo.add_argument(
        "--saturation",
        choices=("flag", "bridge", "error"),
        default="flag",
        help="saturated samples: report (flag, default), replace by quintic bridges, or refuse",
    )
    lo.add_argument(
        "--gyro-range",
        metavar="RAD_S",
        type=positive_float,
        default=None,
        help="gyro range for the saturation check (default: detect clipping plateaus)",
    )
    lo.add_argument(
        "--accel-range",
        metavar="M_S2",
        type=positive_float,
        default=None,
        help="accelerometer range for the saturation check (default: detect plateaus)",
    )
    lo.add_argument(
        "--no-unit-check",
        action="store_true",
        help="skip the plausibility check of the units (static |f| ≈ g, |ω| < 40 rad/s)",
    )
    ru.add_argument("--json", action="store_true", help="print one JSON object")
    ru.add_argument(
        "--plot",
        metavar="FILE|DIR",
        default=None,
        help="write a top view with the truth to FILE (for a folder: DIR/<name>.png)",
    )
    ru.add_argument(
        "--out",
        metavar="FILE|DIR",
        default=None,
        help="write the track to FILE (CSV: time, position, velocity, attitude, stance, "
        "covariance diagonal; for a folder: DIR/<name>_track.csv)",
    )
    ru.set_defaults(func=_cmd_run)

    si = sub.add_parser(
        "simulate", help="write a simulated foot walk as a CSV recording (docs/REAL_DATA.md)"
    )
    si.add_argument("--out", metavar="FILE", required=True, help="CSV file to write")
    si.add_argument(
        "--speed",
        nargs=2,
        metavar=("LO", "HI"),
        type=positive_float,
        default=None,
        help="range of every stride's speed, m/s (0.1…4; the gait follows from the speed; "
        "default 0.8 1.3 unless --gait)",
    )
    si.add_argument(
        "--gait",
        choices=("slow_walk", "walk", "fast_walk", "run"),
        default=None,
        help="one gait class at its speeds, instead of --speed: slow_walk 0.27-0.67, "
        "walk 0.75-1.2, fast_walk 1.25-1.65, run 2-3.7 m/s (the model applies as with --speed)",
    )
    si.add_argument(
        "--duration",
        metavar="S",
        type=positive_float,
        default=60.0,
        help="s, 5…7200 (default 60); the walk ends with the last stride that fits, so it can "
        "be up to a stride shorter (the message says the length written)",
    )
    si.add_argument(
        "--rate",
        metavar="HZ",
        type=positive_float,
        default=200.0,
        help="Hz, 90…1100, what the loaders read (default 200)",
    )
    si.add_argument(
        "--imu",
        metavar="GRADE",
        default=None,
        help="IMU error grade (default: the calibrated model's, microstrain_gx5)",
    )
    si.add_argument(
        "--stops",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="stand still for 1–5 s at the start of some legs (default on)",
    )
    si.add_argument("--seed", type=nonnegative_int, default=0, help="random seed (default 0)")
    si.add_argument(
        "--model",
        default="calibrated",
        help="the simulator model, as pednav sim2real's --model: calibrated (default), "
        "today, or a fitted-parameter JSON file",
    )
    si.set_defaults(func=_cmd_simulate)
    _add_sim2real(sub)
