"""The seed split: training and evaluation episodes are disjoint by construction.

Every episode is drawn from a generator seeded with one integer (lane i of a
vector env reset with seed s uses s + i; its later episodes continue that
generator). Evaluation uses the first episode of generators seeded in
``[0, TRAIN_SEED_BASE)``; training and the tuned-fixed search use only
generators seeded at ``TRAIN_SEED_BASE`` and above, so no training episode is
ever an evaluation episode.

A training *run seed* r ∈ [0, MAX_RUN_SEED) owns the block of lane seeds
``TRAIN_SEED_BASE + r · LANES_PER_RUN + [0, LANES_PER_RUN)``
(:func:`training_seed`); :class:`pednav_env.sb3.NativeVecEnv` maps SB3's
``seed(r)`` (what ``PPO(seed=r)`` calls) into that block.
"""

from __future__ import annotations

#: Evaluation seeds are below this, training seeds at or above it.
TRAIN_SEED_BASE = 1_000_000
#: Seeds of training run ``seed``: TRAIN_SEED_BASE + seed · LANES_PER_RUN + lane.
LANES_PER_RUN = 10_000
#: Training run seeds are 0 … MAX_RUN_SEED − 1.
MAX_RUN_SEED = 10_000
#: The tuned-fixed search evaluates candidates on these seeds (training side).
SEARCH_SEED = 900_000_000  # tuned-fixed search episodes (training side)
#: A search's result is re-evaluated on fresh training episodes from this seed on
#: (never searched on), so the reported objective is not the best of many draws.
REEVALUATION_SEED = 910_000_000
#: A search may use its own set of training episodes: set k is the seeds
#: ``SEARCH_SEED + k · SEARCH_SET_STRIDE + [0, episodes)`` (:func:`search_seeds`);
#: set 0 (seeds from SEARCH_SEED) is the one every shipped search used. The sets
#: are disjoint and all lie below REEVALUATION_SEED.
SEARCH_SET_STRIDE = 100_000
#: Search episode sets are 0 … MAX_SEARCH_SET − 1.
MAX_SEARCH_SET = (REEVALUATION_SEED - SEARCH_SEED) // SEARCH_SET_STRIDE
#: The final-evaluation range: evaluation seeds kept untouched during development
#: and played once, with the shipped policies, for the published tables
#: (docs/RESULTS.md). Development evaluation uses 5 000 – 9 999 and 20 000 – 29 999.
FINAL_EVALUATION_SEEDS = range(800_000, 801_000)


def check_evaluation_seeds(seed: int, episodes: int) -> None:
    """Raise unless seeds ``seed … seed+episodes−1`` are all evaluation seeds."""
    if seed < 0 or seed + episodes > TRAIN_SEED_BASE:
        raise ValueError(
            f"evaluation seeds must lie in [0, {TRAIN_SEED_BASE}); got seed={seed}, "
            f"episodes={episodes} (seeds ≥ {TRAIN_SEED_BASE} are reserved for training)"
        )


def search_seeds(episode_set: int, episodes: int) -> list[int]:
    """The seeds of search episode set ``episode_set``: ``episodes`` training
    episodes, disjoint from every other set and from the re-evaluation episodes."""
    if not 0 <= episode_set < MAX_SEARCH_SET:
        raise ValueError(f"episode_set must be in [0, {MAX_SEARCH_SET}), got {episode_set}")
    if not 1 <= episodes <= SEARCH_SET_STRIDE:
        raise ValueError(f"episodes must be in [1, {SEARCH_SET_STRIDE}], got {episodes}")
    first = SEARCH_SEED + episode_set * SEARCH_SET_STRIDE
    return list(range(first, first + episodes))


def training_seed(run_seed: int) -> int:
    """First lane seed of training run ``run_seed`` (≥ TRAIN_SEED_BASE)."""
    if not 0 <= run_seed < MAX_RUN_SEED:
        raise ValueError(f"seed must be in [0, {MAX_RUN_SEED}) for training, got {run_seed}")
    return TRAIN_SEED_BASE + run_seed * LANES_PER_RUN
