"""What the native environments share.

An env module is its manual (the class docstring) plus a few lines: a subclass
of :class:`NativeScalarEnv` and of :class:`NativeVectorEnv` naming its
``env_id``, its core class ``core_cls`` (a :class:`pednav_env.envs.spec.Core`),
its config class ``config_cls`` and the config fields its constructor takes as
keyword ``arguments``. Both constructors are here: ``config`` (or the defaults
of ``config_cls``) with the given arguments replaced.

:class:`NativeScalarEnv` — a scalar env is its batched core with one lane:
action check, lane-0 info, the render track (kept only when a render
mode is set, so memory stays flat) and the matplotlib rendering.

:class:`NativeVectorEnv` — lane seeding and SAME_STEP autoreset.

A native vector env wraps a batched episode core and steps all
lanes in one call chain. Seeding: ``reset(seed=s)`` gives lane i the
generator ``seeding.np_random(s + i)`` — the one a scalar env reset with seed
s + i uses — and a lane's later episodes continue its generator, as a scalar
env's ``reset()`` without a seed does. Autoreset mode SAME_STEP: a finished
lane is reset within the same ``step``; its last observation and info are in
``info["final_obs"]`` / ``info["final_info"]`` (masks ``_final_obs`` /
``_final_info``), as Gymnasium's SyncVectorEnv does in that mode.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any, ClassVar, TypeVar

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv

from pednav_env.envs.spec import Core, validate_action

ConfigT = TypeVar("ConfigT")


def make_config(cls: type[ConfigT], config: ConfigT | None, **overrides: Any) -> ConfigT:
    """An env's frozen config from its constructor arguments: ``config`` (or the
    defaults of ``cls``) with the keyword arguments that were given (not None)
    replaced."""
    fields = {k: v for k, v in overrides.items() if v is not None}
    if config is None:
        return cls(**fields)
    return replace(config, **fields) if fields else config  # type: ignore[type-var]


class EnvFront:
    """What the scalar and vector env classes of one environment declare."""

    #: The registered id, e.g. ``"pednav/FootZupt-v0"`` (named in every error).
    env_id: ClassVar[str]
    #: The batched core, built as ``core_cls(config, num_lanes, env_id)``.
    core_cls: ClassVar[type]
    #: The frozen config dataclass the constructor builds.
    config_cls: ClassVar[type]
    #: Fields of ``config_cls`` the constructor also takes as keyword arguments.
    arguments: ClassVar[tuple[str, ...]] = ()
    core: Core
    config: Any

    @classmethod
    def build_config(cls, config: Any, arguments: dict[str, Any]) -> Any:
        """``config`` (or the defaults) with the keyword ``arguments`` given
        (not None) replaced; an argument the env does not take is a TypeError
        naming it, as Python's own for an unexpected keyword."""
        unknown = sorted(set(arguments) - set(cls.arguments))
        if unknown:
            raise TypeError(
                f"{cls.env_id}: unexpected argument(s) {unknown}; "
                f"takes config, render_mode and {list(cls.arguments)}"
            )
        return make_config(cls.config_cls, config, **arguments)

    def action_dim(self) -> int:
        """Length of one lane's action (the number of knobs)."""
        return int(self.config.action_dim)


class NativeScalarEnv(EnvFront, gym.Env):
    """Base class of the scalar envs: one lane of ``core_cls``.

    Hooks: :meth:`lane_info` (scalars describing the episode),
    :meth:`record_track` / :meth:`draw` (what the render shows).
    """

    metadata = {"render_modes": ["rgb_array", "human"], "render_fps": 4}
    #: Dimension of the plotted track points, and the figure size (inches).
    track_dim = 2
    figure_size = (5.0, 5.0)
    estimate_label = "estimate"
    _figure = None

    def __init__(
        self, *, config: Any = None, render_mode: str | None = None, **arguments: Any
    ) -> None:
        self.check_render_mode(render_mode)
        self.render_mode = render_mode
        self.config = self.build_config(config, arguments)
        self.core = self.core_cls(self.config, 1, self.env_id)
        self.action_space, self.observation_space = lane_spaces(self.core, self.action_dim())

    def check_render_mode(self, render_mode: str | None) -> None:
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"{self.env_id}: render_mode must be one of "
                f"{self.metadata['render_modes']}, got {render_mode!r}"
            )

    def lane_info(self) -> dict[str, Any]:
        """Scalars describing the current episode (e.g. the sensor grade)."""
        return {}

    def knobs(self) -> dict[str, float]:
        return {k: float(v[0]) for k, v in self.core.knob_values().items()}

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        self.core.reset_lanes(np.array([0]), [self.np_random])
        self._track_true: list[np.ndarray] = [np.zeros(self.track_dim)]
        self._track_est: list[np.ndarray] = [np.zeros(self.track_dim)]
        info = {**self.lane_info(), "distance": 0.0, "error": 0.0, "knobs": self.knobs()}
        return self.core.obs[0].copy(), info

    def step(self, action):
        a = validate_action(action, self.action_space.shape, self.env_id)
        obs, reward, terminated, truncated, info = self.core.step(a[None, :])
        out = {k: (v[0].copy() if np.ndim(v) > 1 else v[0].item()) for k, v in info.items()}
        out.update(self.lane_info())
        out["knobs"] = self.knobs()
        if self.render_mode is not None:  # the track is kept only for rendering
            self.record_track(out)
        if self.render_mode == "human":
            self.render()
        return obs[0], float(reward[0]), bool(terminated[0]), bool(truncated[0]), out

    def record_track(self, info: dict[str, Any]) -> None:
        """Append this interval's truth and estimate to the render track."""
        self._track_true.append(info["pos_true"][: self.track_dim])
        self._track_est.append(info["pos_est"][: self.track_dim])

    def draw(self, ax: Any) -> None:
        """Truth vs estimate in the horizontal plane."""
        t = np.array(self._track_true)
        e = np.array(self._track_est)
        ax.plot(t[:, 0], t[:, 1], "k-", label="truth")
        ax.plot(e[:, 0], e[:, 1], "r--", label=self.estimate_label)
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel("east (m)")
        ax.set_ylabel("north (m)")
        ax.legend(loc="upper right")

    def render(self):
        if self.render_mode is None:
            gym.logger.warn(f"{self.core.env_name}: render() called without a render_mode")
            return None
        import matplotlib

        if self.render_mode == "rgb_array":
            matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        if self._figure is None:
            self._figure = plt.figure(figsize=self.figure_size, dpi=80)
        fig = self._figure
        fig.clf()
        self.draw(fig.add_subplot(111))
        fig.canvas.draw()
        if self.render_mode == "human":
            plt.pause(0.001)
            return None
        return np.asarray(fig.canvas.buffer_rgba())[..., :3].copy()

    def close(self):
        if self._figure is not None:
            import matplotlib.pyplot as plt

            plt.close(self._figure)
            self._figure = None


def lane_spaces(core: Core, action_dim: int) -> tuple[spaces.Box, spaces.Box]:
    """Action space Box(-1, 1, (action_dim,)) and observation space of one lane of
    ``core`` (bounds ``core.obs_low`` / ``core.obs_high``)."""
    action = spaces.Box(-1.0, 1.0, (action_dim,), np.float32)
    return action, spaces.Box(core.obs_low, core.obs_high, dtype=np.float32)


class NativeVectorEnv(EnvFront, VectorEnv):
    """Base class of the vector envs: ``num_envs`` lanes of ``core_cls``.

    A subclass names its scalar env as ``scalar_env`` and gets that env's
    ``env_id``, ``core_cls``, ``config_cls``, ``arguments`` and ``action_dim``.
    """

    metadata = {"autoreset_mode": AutoresetMode.SAME_STEP, "render_modes": []}
    scalar_env: ClassVar[type[NativeScalarEnv]]
    _lane_rngs: list[np.random.Generator] | None = None

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        scalar = cls.__dict__.get("scalar_env")
        if scalar is not None:
            for name in ("env_id", "core_cls", "config_cls", "arguments", "action_dim"):
                setattr(cls, name, getattr(scalar, name))

    def __init__(
        self,
        num_envs: int = 1,
        *,
        config: Any = None,
        render_mode: str | None = None,
        **arguments: Any,
    ) -> None:
        if render_mode is not None:  # the scalar versions render
            raise ValueError(f"{self.env_id}: the vector env does not render; got {render_mode!r}")
        self.config = self.build_config(config, arguments)
        self.attach_core(self.core_cls(self.config, int(num_envs), self.env_id))

    def attach_core(self, core: Core) -> None:
        """Use ``core`` (its N lanes) and set the single-lane and batched spaces."""
        self.core = core
        self.num_envs = int(core.n)
        action_dim = self.action_dim()
        self.single_action_space, self.single_observation_space = lane_spaces(core, action_dim)
        self.action_space = spaces.Box(-1.0, 1.0, (self.num_envs, action_dim), np.float32)
        self.observation_space = spaces.Box(
            np.tile(core.obs_low, (self.num_envs, 1)),
            np.tile(core.obs_high, (self.num_envs, 1)),
            dtype=np.float32,
        )
        self.render_mode = None

    def lane_info(self) -> dict[str, np.ndarray]:
        """Per-lane descriptors of the current episodes (e.g. the sensor grade)."""
        return {}

    def reset(self, *, seed: int | list[int | None] | None = None, options: dict | None = None):
        if isinstance(seed, int | np.integer):
            seeds: list[int | None] = [int(seed) + i for i in range(self.num_envs)]
        elif seed is None or all(s is None for s in seed):
            seed = None
            seeds = [None] * self.num_envs
        else:
            seeds = list(seed)
            if len(seeds) != self.num_envs:
                raise ValueError(
                    f"{self.core.env_name}: {len(seeds)} seeds for {self.num_envs} envs"
                )
        if seed is not None or self._lane_rngs is None:
            self._lane_rngs = [seeding.np_random(s)[0] for s in seeds]
        self.core.reset_lanes(np.arange(self.num_envs), self._lane_rngs)
        return self.core.obs.copy(), self.lane_info()

    def step(self, actions):
        if self._lane_rngs is None:
            raise RuntimeError(f"{self.env_id}: call reset() before step()")
        actions = validate_action(actions, self.action_space.shape, self.env_id)
        obs, reward, terminated, truncated, info = self.core.step(actions)
        info.update(self.lane_info())
        done = terminated | truncated
        if done.any():
            lanes = np.flatnonzero(done)
            info["final_obs"] = np.full(self.num_envs, None, dtype=object)
            info["final_info"] = np.full(self.num_envs, None, dtype=object)
            for lane in lanes:
                info["final_obs"][lane] = obs[lane].copy()
                info["final_info"][lane] = {
                    k: v[lane] for k, v in info.items() if k not in ("final_obs", "final_info")
                }
            info["_final_obs"] = done.copy()
            info["_final_info"] = done.copy()
            self.core.reset_lanes(lanes, [self._lane_rngs[i] for i in lanes])
            obs = self.core.obs.copy()
            info.update(self.lane_info())
        return obs, reward.astype(np.float64), terminated, truncated, info
