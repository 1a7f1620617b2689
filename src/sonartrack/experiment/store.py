"""Trial store: chunked Parquet files, written atomically, keyed by a hash of the resolved config.

Layout under a study's output folder::

    <out>/<study>/cache/<key>/trials-<first>-<stop>.parquet    one chunk: trials first..stop-1
    <out>/<study>/trials.parquet                                all trials of the last run

Every file is written through :func:`sonartrack.io.atomic.atomic_path` (a temporary sibling renamed
into place), so a chunk file that exists is complete. One row per trial; each array-valued key is one
list<float64/int64> column holding the flattened array, and its per-trial shape and dtype sit in the
schema metadata.
The key hashes the study id, its ``TRIAL_VERSION``, the config without ``runs``, and the master
seed: asking for more runs reuses every trial already on disk.
"""

from __future__ import annotations

import hashlib
import json
import re
from pathlib import Path

import numpy as np

from sonartrack.io.atomic import atomic_path

_CHUNK_RE = re.compile(r"^trials-(\d+)-(\d+)\.parquet$")


def config_key(study_id: str, trial_version: int, config_dict: dict, seed: int) -> str:
    """A short, stable hash of everything that determines a trial's numbers (not ``runs``).

    Parameters
    ----------
    study_id : str
        Study identifier.
    trial_version : int
        The study's ``TRIAL_VERSION`` (bumped when a trial's numbers change).
    config_dict : dict
        The config as JSON data (``runs`` is ignored).
    seed : int
        Master seed.

    Returns
    -------
    str
        First 16 hex digits of the SHA-256 of the canonical JSON.
    """
    payload = {k: v for k, v in config_dict.items() if k != "runs"}
    text = json.dumps({"study": study_id, "version": trial_version, "config": payload, "seed": int(seed)},
                      sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _table_from_trials(indices, trials: dict[str, np.ndarray]):
    import pyarrow as pa

    meta = {}
    columns = {"trial": pa.array(np.asarray(indices, dtype=np.int64))}
    n = len(indices)
    for key, arr in trials.items():
        arr = np.asarray(arr)
        if arr.shape[0] != n:
            raise ValueError(f"trial output '{key}' has {arr.shape[0]} rows for {n} trials")
        kind = "int" if np.issubdtype(arr.dtype, np.integer) or arr.dtype == bool else "float"
        dtype = np.int64 if kind == "int" else np.float64
        flat = arr.reshape(n, -1).astype(dtype)
        per = flat.shape[1]
        values = pa.array(flat.ravel())
        offsets = pa.array(np.arange(0, (n + 1) * per, per, dtype=np.int32) if per else np.zeros(n + 1, np.int32))
        columns[key] = pa.ListArray.from_arrays(offsets, values)
        meta[key] = {"shape": list(arr.shape[1:]), "kind": kind, "bool": arr.dtype == bool}
    table = pa.table(columns)
    return table.replace_schema_metadata({"sonartrack": json.dumps(meta)})


def write_chunk(folder: Path, indices, trials: dict[str, np.ndarray]) -> Path:
    """Write trials ``indices`` (contiguous) to one Parquet chunk file, atomically.

    Parameters
    ----------
    folder : pathlib.Path
        Cache folder (created if missing).
    indices : sequence of int
        Contiguous trial indices.
    trials : dict of str to ndarray
        Outputs, first axis the trials.

    Returns
    -------
    pathlib.Path
        The final file, ``trials-<first>-<stop>.parquet``.
    """
    import pyarrow.parquet as pq

    folder.mkdir(parents=True, exist_ok=True)
    first, stop = int(indices[0]), int(indices[-1]) + 1
    final = folder / f"trials-{first:06d}-{stop:06d}.parquet"
    with atomic_path(final) as tmp:
        pq.write_table(_table_from_trials(indices, trials), tmp)
    return final


def read_table(path: Path) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Read one trials file.

    Parameters
    ----------
    path : pathlib.Path
        A chunk file or trials.parquet.

    Returns
    -------
    indices : ndarray of int64
        Trial indices.
    trials : dict of str to ndarray
        Each output stacked over its trials, with its stored per-trial shape and dtype.
    """
    import pyarrow.parquet as pq

    table = pq.read_table(path)
    meta = json.loads(table.schema.metadata[b"sonartrack"])
    indices = table.column("trial").to_numpy()
    out = {}
    for key, m in meta.items():
        col = table.column(key).combine_chunks()
        flat = col.flatten().to_numpy(zero_copy_only=False)
        arr = flat.reshape((len(indices), *m["shape"]))
        if m.get("bool"):
            arr = arr.astype(bool)
        out[key] = arr
    return indices, out


def done_indices(folder: Path) -> set[int]:
    """Trial indices already stored in complete chunk files under ``folder``.

    Parameters
    ----------
    folder : pathlib.Path
        Cache folder (may not exist).

    Returns
    -------
    set of int
        Stored trial indices.
    """
    done: set[int] = set()
    if folder.is_dir():
        for p in folder.iterdir():
            m = _CHUNK_RE.match(p.name)
            if m:
                done.update(range(int(m.group(1)), int(m.group(2))))
    return done


def load_trials(folder: Path, runs: int) -> dict[str, np.ndarray]:
    """Gather trials 0..runs-1 from the chunk files, in trial order.

    Parameters
    ----------
    folder : pathlib.Path
        Cache folder.
    runs : int
        Trials wanted.

    Returns
    -------
    dict of str to ndarray
        Each output stacked over the runs.

    Raises
    ------
    RuntimeError
        If a trial is missing.
    """
    parts: dict[int, dict[str, np.ndarray]] = {}
    for p in sorted(folder.iterdir()):
        m = _CHUNK_RE.match(p.name)
        if not m or int(m.group(1)) >= runs:
            continue
        idx, arrays = read_table(p)
        for row, i in enumerate(idx):
            if i < runs and i not in parts:
                parts[int(i)] = {k: v[row] for k, v in arrays.items()}
    missing = sorted(set(range(runs)) - parts.keys())
    if missing:
        raise RuntimeError(f"trials missing from the store: {missing[:5]}...")
    keys = parts[0].keys()
    return {k: np.stack([parts[i][k] for i in range(runs)]) for k in keys}


def write_trials_file(path: Path, trials: dict[str, np.ndarray]) -> None:
    """Write all trials of a run to one Parquet file, atomically.

    Parameters
    ----------
    path : pathlib.Path
        Output file (its folder is created).
    trials : dict of str to ndarray
        Outputs, first axis the trials.
    """
    import pyarrow.parquet as pq

    n = len(next(iter(trials.values())))
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        pq.write_table(_table_from_trials(np.arange(n), trials), tmp)
