"""``pednav/MarkerTrack-v0``: retune the heel–knee marker EKF online (paper 001)."""

from __future__ import annotations

from typing import Any

import numpy as np

from pednav_env.envs.marker_config import ACTION_KNOBS, MarkerTrackConfig
from pednav_env.envs.marker_core import OBS_FEATURES, MarkerTrackCore
from pednav_env.envs.native import NativeScalarEnv, NativeVectorEnv

ENV_ID = "pednav/MarkerTrack-v0"
#: Seconds of track shown by :meth:`MarkerTrackEnv.render`.
RENDER_WINDOW_S = 3.0


class MarkerTrackEnv(NativeScalarEnv):
    """
    ## Description
    A walker wears two UWB tags on one leg, on the heel and on the knee; the
    extended Kalman filter of paper 001 (VR-tracking thesis, chapter 5)
    smooths their raw positions with a harmonic gait model (eq 4.10: trend
    plus the fundamental gait harmonic, shank of fixed length M) whose six
    parameter deviations [ΔA_x, ΔA_z, Δc_x, Δc_z, ΔA, Δω] it estimates. Every
    ``decision_interval_s`` (0.5 s = 5 UWB samples at 10 Hz) the agent retunes
    the filter: the process-noise scale of each parameter group and the
    measurement-noise scale. It is scored on the RMS error of the filtered
    heel and knee positions (x forward, z up). Action 0 is exactly the
    thesis's filter, so the zero policy is the paper baseline.

    Episodes are drawn from the reset seed (domain randomisation): a walk of
    60–180 s of the heel–knee model with integrated kinematics; the walker's
    own parameters (amplitudes, speed, heel height, shank swing, cadence)
    drawn from the thesis's stationary law (17 % std each, eqs 5.4, 5.8) and
    drifting with a 100 s correlation time; gait changes (Poisson, one per
    20 s on average) to a new cadence and stride (factors 0.85–1.15, so the
    speed changes by 0.72–1.32×) with 1 s transitions. The UWB condition is
    one of ``clean`` (σ = 0.1 m), ``noisy`` (σ = 0.25 m), ``nlos`` (bursts of
    biased, noisier, often dropped samples), ``outliers`` (5 % of 1 m),
    ``dropouts`` (25 % lost samples) or ``realistic`` (a mix), with σ scaled
    by a factor 0.7–1.5. ``scenario="paper"`` gives the thesis setup: eq 4.10
    taken literally, 10 s walks starting at the nominal gait, σ = 0.1 m.

    Long walks: the thesis's model multiplies the rate parameters by the
    elapsed time kT; the filter writes it about a time origin that is
    re-anchored (every 8 s, to a gait-cycle boundary 3 s back; an exact
    reparametrisation of the current estimate) — see
    :mod:`pednav_env.envs.marker_core`. The paper scenario never re-anchors.

    ## Action Space
    ``Box(-1, 1, (4,), float32)``. Component i sets knob i to
    ``base_i · span_i ** a_i``:

    | Num | Knob | Base (paper) | Span | Range | Unit |
    |-----|------|--------------|------|-------|------|
    | 0 | Q scale of ΔA_x, ΔA_z, ΔA (× thesis Γ Q Γᵀ, eq 5.4) | 1 | 1000 | 0.001–1000 | 1 |
    | 1 | Q scale of the trend Δc_x, Δc_z | 1 | 1000 | 0.001–1000 | 1 |
    | 2 | Q scale of the cadence Δω | 1 | 1000 | 0.001–1000 | 1 |
    | 3 | R scale (× thesis R = 0.01 I m², eq 5.5) | 1 | 100 | 0.01–100 | 1 |

    Actions outside [-1, 1] are clipped and counted (``info["clipped_actions"]``);
    wrong shapes, NaN or inf raise ``ValueError``.

    ## Observation Space
    ``Box(low, high, (29,), float32)``, from the UWB data and the filter only
    (never the truth); values are clipped to the bounds below. ν are the
    normalised sequential innovations of the interval's updates (the four
    coordinates processed one after another; Σ ν² is the NIS).

    | Num | Observation | Min | Max | Unit |
    |-----|-------------|-----|-----|------|
    | 0 | fraction of marker samples dropped in the interval | 0 | 1 | 1 |
    | 1 | mean log(1 + NIS) over the interval's updates | 0 | 30 | 1 |
    | 2 | max log(1 + NIS) | 0 | 30 | 1 |
    | 3 | fraction of updates with NIS above its χ² 99 % quantile | 0 | 1 | 1 |
    | 4–7 | RMS of ν: heel x, heel z, knee x, knee z | 0 | 100 | 1 |
    | 8–11 | mean of ν (bias indicator), same order | −100 | 100 | 1 |
    | 12–17 | log₁₀ (√P_ii / \\|p⁰_i\\|) of A_x, A_z, c_x, c_z, A, ω | −8 | 4 | 1 |
    | 18–23 | estimated deviations Δp̂_i / \\|p⁰_i\\|, same order | −10 | 10 | 1 |
    | 24 | time since the filter's time origin t − t_a | 0 | 3600 | s |
    | 25–28 | the action in force (one entry per knob) | −1 | 1 | 1 |

    Right after reset no sample has been processed: entries 0–11 are 0.

    ## Rewards
    ``−e · n / K`` per step: e is the RMS marker position error over the
    interval's samples (heel and knee, x and z: √(mean of the squared
    errors)), n the interval's samples and K the walk's; the return is minus
    the time-averaged RMS marker error (m). ``info["reward_error"]`` carries
    that term.

    ## Starting State
    The filter starts at the thesis's prior: zero deviations (eq 5.7) and
    P0 = 0.03 diag(p⁰²) (eq 5.8); the first step processes the walk's first
    samples (the first one is a correction from the prior).

    ## Episode End
    - Truncation: the end of the walk.
    - Termination (divergence): a non-finite filter state or covariance, a
      cadence estimate outside 0.25–4 × ω₀, or lock loss — the interval's RMS
      marker error above 1 m (the filter has locked onto another gait cycle or
      lost the trend; it does not recover). The final error is then held for
      the rest of the walk in the last reward (a non-finite error counts as
      10 m), so the return is still minus the time-averaged error and
      diverging never pays.

    ## Arguments
    ``gymnasium.make("pednav/MarkerTrack-v0", scenario="random", decision_interval_s=0.5,
    rate_hz=10.0, config=None, render_mode=None)``; ``config`` is a full
    :class:`pednav_env.envs.marker_config.MarkerTrackConfig`.

    ## Vectorized environment
    ``gymnasium.make_vec("pednav/MarkerTrack-v0", num_envs=N,
    vectorization_mode="vector_entry_point")`` gives :class:`MarkerTrackVectorEnv`:
    all N walks step through one batched filter. Autoreset mode: SAME_STEP
    (the reset observation is returned at once; the last one is in
    ``info["final_obs"]``, its info in ``info["final_info"]``). Lane i of a
    vector env reset with seed s plays the same episodes, bit for bit, as
    this env reset with seed s + i.

    ## Info
    ``markers_true``, ``markers_est`` (heel x, heel z, knee x, knee z at the
    interval's last sample, m), ``error`` (the interval's RMS marker error, m),
    ``error_by_coord`` (per coordinate, m), ``distance`` (heel's forward
    distance from the start, m), ``samples``, ``dropped_samples`` (marker
    samples lost in the interval), ``reanchors``, ``clipped_actions``,
    ``covariance_repairs``, ``diverged``, ``lock_lost``, ``reward_error``,
    ``uwb_condition``, ``knobs`` (physical values). ``context`` is privileged
    truth for oracle policies only (never part of the observation): the UWB
    condition's index in ``config.uwb_conditions`` (−1 in the paper scenario)
    and the factor on its σ, in the order of
    :data:`pednav_env.envs.marker_config.CONTEXT_FIELDS`.

    ## Example
    >>> import gymnasium as gym, numpy as np, pednav_env
    >>> env = gym.make("pednav/MarkerTrack-v0", scenario="paper")
    >>> obs, info = env.reset(seed=0)
    >>> obs.shape
    (29,)
    >>> obs, reward, terminated, truncated, info = env.step(np.zeros(4, np.float32))
    >>> bool(reward <= 0), info["samples"]
    (True, 5)

    ## Version History
    - v0: initial version.
    """

    env_id = ENV_ID
    core_cls = MarkerTrackCore
    config_cls = MarkerTrackConfig
    arguments = ("scenario", "decision_interval_s", "rate_hz")
    figure_size = (6.0, 4.0)
    track_dim = 4

    def lane_info(self) -> dict[str, Any]:
        return {"uwb_condition": self.core.condition[0], "context": self.core.context[0].copy()}

    def record_track(self, info: dict[str, Any]) -> None:
        """Marker tracks of the interval's samples, the last RENDER_WINDOW_S seconds."""
        active = self.core.interval_active[:, 0]
        self._track_true.extend(self.core.interval_truth[active, :, 0])
        self._track_est.extend(self.core.interval_est[active, :, 0])
        keep = int(RENDER_WINDOW_S * self.config.rate_hz)
        del self._track_true[:-keep], self._track_est[:-keep]

    def draw(self, ax: Any) -> None:
        """Heel and knee, truth vs EKF, in the sagittal plane."""
        t = np.array(self._track_true[1:]).reshape(-1, 4)
        e = np.array(self._track_est[1:]).reshape(-1, 4)
        for col, name, colour in ((0, "heel", "tab:blue"), (2, "knee", "tab:orange")):
            ax.plot(t[:, col], t[:, col + 1], "-", color=colour, label=f"{name} truth")
            ax.plot(e[:, col], e[:, col + 1], "--", color=colour, label=f"{name} EKF")
        ax.set_xlabel("x forward (m)")
        ax.set_ylabel("z up (m)")
        ax.set_title(f"last {RENDER_WINDOW_S:g} s")
        ax.legend(loc="upper left", fontsize="small")


class MarkerTrackVectorEnv(NativeVectorEnv):
    """Native vector version of :class:`MarkerTrackEnv` (see its docstring):
    one batched filter for all ``num_envs`` walks, SAME_STEP autoreset."""

    scalar_env = MarkerTrackEnv

    def lane_info(self) -> dict[str, np.ndarray]:
        return {"uwb_condition": self.core.condition.copy(), "context": self.core.context.copy()}


# ACTION_KNOBS / OBS_FEATURES are re-exported for documentation tools.
__all__ = ["ACTION_KNOBS", "ENV_ID", "OBS_FEATURES", "MarkerTrackEnv", "MarkerTrackVectorEnv"]
