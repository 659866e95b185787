"""A run directory holds one run: what ``pednav train`` and ``pednav distill`` find there
from earlier runs, and refuse or remove before they write.

Both commands write into ``--run-dir`` either one run (the directory itself) or, for
several seeds, one run per seed in ``<prefix>seed<S>`` sub-directories (``ppo_seed0``
for ``pednav train --seeds``, ``seed0`` for ``pednav distill --seeds``). A new run
written beside an earlier one would mix with it: the earlier run's checkpoints (which
``pednav train --resume`` picks by step count) and TensorBoard logs in a re-used run
directory, other seeds' runs or an earlier single run beside a new set of seeds, seed
sub-directories beside a new single run. :func:`stale_outputs` lists what is there,
:func:`claim_run_dirs` refuses it in one line (a ``ValueError`` naming ``--run-dir``) or,
with ``--overwrite``, removes it first (:func:`remove_outputs`). Files of the user's own
in a run directory are never listed.
"""

from __future__ import annotations

import re
import shutil
from collections.abc import Sequence
from pathlib import Path

from pednav_env.seeds import training_seed

#: What a run writes into its run directory (``pednav distill`` only the first three).
RUN_OUTPUTS = ("model.zip", "vecnormalize.pkl", "meta.json", "checkpoints", "tb")


def check_seeds(seeds: Sequence[int]) -> None:
    """ValueError unless ``seeds`` are one or more distinct training run seeds."""
    if not seeds:
        raise ValueError("seeds: give at least one training seed")
    if len(set(seeds)) != len(seeds):
        raise ValueError(f"seeds must be distinct, got {list(seeds)}")
    for s in seeds:
        training_seed(s)  # ValueError for a seed outside the training range


def stale_outputs(
    base: str | Path,
    run_dirs: Sequence[str | Path],
    seed_prefix: str,
    resume: bool = False,
) -> list[Path]:
    """What earlier runs left in ``base`` (the ``--run-dir``) that a new run into
    ``run_dirs`` (``[base]`` for one run, else ``base/<seed_prefix>seed<S>`` per seed)
    would mix with its own: the :data:`RUN_OUTPUTS` already in each of ``run_dirs``
    (none with ``resume``, which continues them), those in ``base`` when it is not one
    of ``run_dirs`` (an earlier single run), and the ``<seed_prefix>seed<S>`` directories
    in ``base`` that are not one of ``run_dirs``. Sorted, each path once."""
    base = Path(base)
    runs = [Path(d) for d in run_dirs]
    found: set[Path] = set()
    if not resume:
        found.update(d / name for d in runs for name in RUN_OUTPUTS if (d / name).exists())
    if base not in runs:
        found.update(base / name for name in RUN_OUTPUTS if (base / name).exists())
    if base.is_dir():
        pattern = re.compile(rf"{re.escape(seed_prefix)}seed\d+")
        for path in base.iterdir():
            if pattern.fullmatch(path.name) and path.is_dir() and path not in runs:
                found.add(path)
    return sorted(found)


def remove_outputs(paths: Sequence[Path]) -> None:
    """Delete ``paths`` (files, or directories with their contents)."""
    for path in paths:
        if path.is_dir() and not path.is_symlink():
            shutil.rmtree(path)
        else:
            path.unlink()


def claim_run_dirs(
    base: str | Path,
    run_dirs: Sequence[str | Path],
    seed_prefix: str,
    overwrite: bool,
    resume: bool | None = None,
) -> list[Path]:
    """Make ``base`` hold only the runs about to be written into ``run_dirs``
    (:func:`stale_outputs`): with ``overwrite`` remove what earlier runs left and return
    it, else a ValueError naming it (nothing is removed). ``resume`` None: the command
    has no ``--resume`` to suggest."""
    base = Path(base)
    runs = [Path(d) for d in run_dirs]
    stale = stale_outputs(base, runs, seed_prefix, bool(resume))
    if not stale or overwrite:
        remove_outputs(stale)
        return stale
    own = [p for p in stale if p.parent in runs and p.name in RUN_OUTPUTS]
    beside = [p.name for p in stale if p.parent == base and p not in own]
    single = [name for name in beside if name in RUN_OUTPUTS]
    seeds = [name for name in beside if name not in RUN_OUTPUTS]
    single_run = runs == [base]
    parts = []
    if own and single_run:
        parts.append(f"holds an earlier run ({', '.join(p.name for p in own)})")
    elif own:
        parts.append(f"earlier runs in {', '.join(sorted({p.parent.name for p in own}))}")
    if single:
        parts.append(f"an earlier single run ({', '.join(single)})")
    if seeds:
        which = "other seeds" if single_run else "seeds not in --seeds"
        parts.append(f"runs of {which}: {', '.join(seeds)}")
    them = "it" if single_run and not seeds else "them"
    then = f"give --overwrite to remove {them} first"
    if resume is not None and not single and not seeds:
        then = f"give --resume to continue {them} or --overwrite to remove {them} first"
    raise ValueError(f"--run-dir {base}: {'; '.join(parts)}; {then}")
