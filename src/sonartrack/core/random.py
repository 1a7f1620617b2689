"""Random streams: every trial draws from its own Generator, spawned from one SeedSequence.

Trial i gets ``SeedSequence(seed, spawn_key=(i,))``, which is exactly the i-th child that
``SeedSequence(seed).spawn(...)`` would return, without spawning the i - 1 before it. A trial's
numbers therefore depend on (seed, i) only: not on the number of workers, the chunking, or the
order in which trials run.
"""

import numpy as np


def trial_seed_sequence(seed: int, trial_index: int) -> np.random.SeedSequence:
    """The SeedSequence of trial ``trial_index`` under master ``seed``: ``SeedSequence(seed, spawn_key=(i,))``.

    Parameters
    ----------
    seed : int
        Master seed of the run.
    trial_index : int
        Index i of the trial (0-based).

    Returns
    -------
    numpy.random.SeedSequence
        The i-th child that ``SeedSequence(seed).spawn`` would return.
    """
    return np.random.SeedSequence(int(seed), spawn_key=(int(trial_index),))


def trial_rng(seed: int, trial_index: int) -> np.random.Generator:
    """The random Generator (PCG64) of trial ``trial_index`` under master ``seed`` (the parameters of
    :func:`trial_seed_sequence`).

    Returns
    -------
    numpy.random.Generator
        A generator that depends on (seed, trial_index) only.
    """
    return np.random.Generator(np.random.PCG64(trial_seed_sequence(seed, trial_index)))
