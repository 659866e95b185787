"""pednav_env — gait-aware pedestrian navigation environments.

Conventions (docs/CONVENTIONS.md):

- SI units inside; angles in radians; a name with another unit says it
  (``rate_hz``, ``heading_deg``). Gravity g = 9.80665 m/s² unless a paper
  says otherwise (always a parameter).
- Navigation frame: local level, x₁ east, x₂ north, x₃ up (the papers' Cx).
  Body frame: x forward, y left, z up. Gravity vector (0, 0, −g); specific
  force f = a − g_vec (at rest and level an accelerometer reads (0, 0, +g)).
- Attitude: quaternion ``q_nb`` body → navigation, scalar first; Euler yaw ψ,
  pitch θ, roll γ in paper 003's 3-2-1 order.
- Arrays are batched: walkers/episodes first, then time: ``(N, T, 3)``.
- Randomness only from ``numpy.random.Generator`` objects passed in (one
  per walker) or derived from an env's ``reset(seed=...)``.
"""

from gymnasium.envs.registration import register, registry

__version__ = "0.1.0"

#: (id, module under pednav_env.envs, class name of the scalar env); the vector
#: env is that class name with ``Vector`` before ``Env``.
ENVS = (
    ("pednav/FootZupt-v0", "foot_zupt", "FootZuptEnv"),
    ("pednav/MarkerTrack-v0", "marker_track", "MarkerTrackEnv"),
    ("pednav/WaistStep-v0", "waist_step", "WaistStepEnv"),
    ("pednav/FootZuptReplay-v0", "foot_replay", "FootZuptReplayEnv"),
)

for _env_id, _module, _cls in ENVS:
    if _env_id not in registry:
        register(
            id=_env_id,
            entry_point=f"pednav_env.envs.{_module}:{_cls}",
            vector_entry_point=f"pednav_env.envs.{_module}:{_cls.removesuffix('Env')}VectorEnv",
        )
