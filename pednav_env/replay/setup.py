"""How the ZUPT-UKF is set up for a recording, and the shipped configurations.

A :class:`RealFilterSetup` is the filter configuration (detector, noise
scales, update mode — :class:`pednav_env.nav.zupt_config.ZuptUkfConfig`) plus
what real data need besides: the mounting rotation, the gravity magnitude,
and the bounds of the still window used for alignment.

Shipped setups (``SETUP_NAMES``):

- ``paper`` — paper 003's real-data filter: eq (5) with its real-data
  thresholds ω_max = 0.039 rad/s, Δf_max = 0.15 m/s²; ZUPTs at stance start
  and end; the gyro bias = mean rate of the still start (its calibration);
  its simulation's noise model (the only one it prints).
- ``real-fixed`` — one configuration chosen on the PyShoe development trials
  by the search in :mod:`pednav_env.replay.search` (``real_fixed.json``
  beside this file; docs/REAL_DATA.md).
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

from pednav_env.constants import STANDARD_GRAVITY
from pednav_env.nav.detectors import ShoeDetectorConfig, ThresholdDetectorConfig
from pednav_env.nav.zupt_config import UpdateMode, ZuptUkfConfig

SETUP_NAMES = ("paper", "real-fixed")
REAL_FIXED_FILE = Path(__file__).with_name("real_fixed.json")


@dataclass(frozen=True)
class RealFilterSetup:
    """Filter configuration plus the real-data steps.

    Parameters
    ----------
    filter : the ZUPT-UKF configuration (its ``alignment_s`` is ignored: the
        window is the still start, see ``alignment_max_s``).
    mounting : ``"auto"``, ``"none"`` or a signed axis list
        (:mod:`pednav_env.nav.mounting`).
    gravity : ``"standard"`` (g = 9.80665 m/s²) or ``"static"`` (the mean
        |f| of the alignment window, absorbing the accelerometer's scale error).
    alignment_max_s, alignment_min_s : s, bounds of the still window at the
        start (:mod:`pednav_env.nav.static_start`).
    """

    filter: ZuptUkfConfig = field(
        default_factory=lambda: ZuptUkfConfig(
            detector=ThresholdDetectorConfig.real_data(), calibrate_gyro_bias=True
        )
    )
    mounting: str = "auto"
    gravity: str = "standard"
    alignment_max_s: float = 1.0
    alignment_min_s: float = 0.1

    def __post_init__(self) -> None:
        if not isinstance(self.filter, ZuptUkfConfig):
            raise ValueError(f"RealFilterSetup.filter must be a ZuptUkfConfig, got {self.filter!r}")
        if self.gravity not in ("standard", "static"):
            raise ValueError(
                f"RealFilterSetup.gravity must be 'standard' or 'static', got {self.gravity!r}"
            )
        if not isinstance(self.mounting, str):
            raise ValueError(f"RealFilterSetup.mounting must be a string, got {self.mounting!r}")
        if self.mounting not in ("auto", "none"):
            from pednav_env.nav.mounting import axes_rotation

            axes_rotation(self.mounting)  # validates
        for name in ("alignment_max_s", "alignment_min_s"):
            v = getattr(self, name)
            if not (isinstance(v, int | float) and math.isfinite(v) and v > 0):
                raise ValueError(f"RealFilterSetup.{name} must be > 0, got {v!r}")
        if self.alignment_min_s > self.alignment_max_s:
            raise ValueError("RealFilterSetup.alignment_min_s must be ≤ alignment_max_s")

    def with_gravity(self, g: float) -> RealFilterSetup:
        """The same setup with gravity magnitude ``g`` in the filter and its detector."""
        det = replace(self.filter.detector, g=g)
        return replace(self, filter=replace(self.filter, g=g, detector=det))

    # ------------------------------------------------------------------ (de)serialisation
    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-able dictionary (inverse of :meth:`from_dict`)."""
        f = self.filter
        det = f.detector
        kind = "shoe" if isinstance(det, ShoeDetectorConfig) else "threshold"
        filt = {k: v for k, v in asdict(f).items() if k not in ("detector", "assumed_imu")}
        filt["update_mode"] = str(f.update_mode)
        d = {"kind": kind, **asdict(det)}
        return {
            "filter": filt,
            "detector": d,
            "assumed_imu": {
                k: (str(v) if k == "drift_model" else v) for k, v in asdict(f.assumed_imu).items()
            },
            "mounting": self.mounting,
            "gravity": self.gravity,
            "alignment_max_s": self.alignment_max_s,
            "alignment_min_s": self.alignment_min_s,
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> RealFilterSetup:
        from pednav_env.sensors.imu import ImuSpec

        det = dict(d["detector"])
        kind = det.pop("kind")
        if kind == "shoe":
            detector = ShoeDetectorConfig(**det)
        elif kind == "threshold":
            detector = ThresholdDetectorConfig(**det)
        else:
            raise ValueError(f"unknown detector kind {kind!r}")
        filt = dict(d["filter"])
        filt["update_mode"] = UpdateMode(filt["update_mode"])
        imu = ImuSpec(**d["assumed_imu"]) if "assumed_imu" in d else ImuSpec.paper003()
        return cls(
            filter=ZuptUkfConfig(detector=detector, assumed_imu=imu, **filt),
            mounting=d.get("mounting", "auto"),
            gravity=d.get("gravity", "standard"),
            alignment_max_s=d.get("alignment_max_s", 1.0),
            alignment_min_s=d.get("alignment_min_s", 0.1),
        )


def paper_setup() -> RealFilterSetup:
    """Paper 003's real-data filter (see the module docstring)."""
    return RealFilterSetup()


def real_fixed_setup(path: Path = REAL_FIXED_FILE) -> RealFilterSetup:
    """The shipped ``real-fixed`` configuration."""
    if not path.exists():
        raise ValueError(f"real-fixed configuration not found: {path}")
    return RealFilterSetup.from_dict(json.loads(path.read_text())["setup"])


def load_setup(path: str | Path) -> RealFilterSetup:
    """A setup from a JSON file: :meth:`RealFilterSetup.to_dict`'s object, or a
    file like ``real_fixed.json`` that holds it under ``"setup"``.

    Raises
    ------
    ValueError
        A missing or unreadable file, or a bad or missing entry (the file named).
    """
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"setup file {path} not found")
    try:
        d = json.loads(path.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise ValueError(f"{path.name}: not a JSON setup file ({exc})") from None
    if isinstance(d, dict) and "setup" in d:
        d = d["setup"]
    if not isinstance(d, dict):
        raise ValueError(f"{path.name}: a setup is a JSON object")
    try:
        return RealFilterSetup.from_dict(d)
    except KeyError as exc:
        raise ValueError(f"{path.name}: the setup has no {exc} entry") from None
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{path.name}: {exc}") from None


def named_setup(name: str) -> RealFilterSetup:
    """A shipped setup by name (``SETUP_NAMES``)."""
    if name == "paper":
        return paper_setup()
    if name == "real-fixed":
        return real_fixed_setup()
    raise ValueError(f"unknown setup {name!r}; use one of {', '.join(SETUP_NAMES)}")


__all__ = [
    "REAL_FIXED_FILE",
    "SETUP_NAMES",
    "STANDARD_GRAVITY",
    "RealFilterSetup",
    "load_setup",
    "named_setup",
    "paper_setup",
    "real_fixed_setup",
]
