"""Per-row state of vessel groups between the tracking steps, kept in memory within a byte
budget or else in files: :class:`Parked`, and the refinement runner over it,
:class:`ParkedGroups`.

A group's :class:`~seatrack.filters.ais.refine.Refinement` keeps its small arrays in memory;
its parts (:attr:`~seatrack.filters.ais.refine.Refinement.PARTS`: the rows, the first track,
the refined state) are parked after every step and loaded again on first use in the next
one, so a step reads only what it needs (the offset update of a group whose offsets did not
change reads only its scores). A part is written once, and a state part again only when the
step changed it (the refinement's ``version``). Files are written with pickle (protocol 5:
the arrays' bytes as they are).
"""

from __future__ import annotations

import functools
import pickle
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seatrack.filters.ais.offsets import OffsetScores
from seatrack.filters.ais.offsets import prior_counts
from seatrack.filters.ais.refine import Refinement

__all__ = ["Parked", "ParkedGroups", "nbytes", "dump", "undump"]


def dump(obj: Any, path: Path) -> None:
    """Pickle ``obj`` to ``path`` (protocol 5)."""
    with path.open("wb") as fh:
        pickle.dump(obj, fh, protocol=5)


def undump(path: Path) -> Any:
    """The object pickled in ``path``."""
    with path.open("rb") as fh:
        return pickle.load(fh)


def nbytes(obj: Any) -> int:
    """Bytes of the NumPy arrays in ``obj`` (arrays, tuples, lists, dicts, dataclasses)."""
    if isinstance(obj, np.ndarray):
        return int(obj.nbytes)
    if isinstance(obj, (tuple, list)):
        return sum(nbytes(x) for x in obj)
    if isinstance(obj, dict):
        return sum(nbytes(x) for x in obj.values())
    fields = getattr(obj, "__dataclass_fields__", None)
    if fields is not None:
        return sum(nbytes(getattr(obj, f)) for f in fields)
    return 0


class Parked:
    """Objects by key, held in memory while their arrays fit in ``budget`` bytes, else
    pickled to ``folder``."""

    def __init__(self, folder: Path, budget: int) -> None:
        self.folder, self.budget = folder, budget
        self.held = 0
        self.mem: dict[str, tuple[Any, int]] = {}
        self.files: dict[str, Path] = {}

    def __contains__(self, key: str) -> bool:
        return key in self.mem or key in self.files

    def put(self, key: str, obj: Any) -> None:
        """Park ``obj`` under ``key`` (replacing what was there)."""
        self.drop(key)
        size = nbytes(obj)
        if self.held + size <= self.budget:
            self.mem[key] = (obj, size)
            self.held += size
            return
        path = self.folder / f"{key}.pkl"
        dump(obj, path)
        self.files[key] = path

    def get(self, key: str) -> Any:
        """The object parked under ``key`` (it stays parked)."""
        if key in self.mem:
            return self.mem[key][0]
        return undump(self.files[key])

    def pop(self, key: str) -> Any:
        """The object parked under ``key``, no longer parked."""
        obj = self.get(key)
        self.drop(key)
        return obj

    def drop(self, key: str) -> None:
        if key in self.mem:
            self.held -= self.mem.pop(key)[1]
        path = self.files.pop(key, None)
        if path is not None:
            path.unlink()


def _load_part(parked: Parked, group: int, name: str) -> Any:
    return parked.get(f"g{group}.{name}")


def ident_scores(ref: Refinement) -> OffsetScores:
    """The identifiable reports' scores of a group (what the prior counts need)."""
    sc = ref.scores()
    keep = np.flatnonzero(sc.ident)
    return OffsetScores(keep, sc.q[keep], np.ones(keep.size, bool), 0)


class ParkedGroups:
    """:class:`~seatrack.filters.ais.refine.GroupRunner` of refinements whose parts are
    parked (:class:`Parked`) between the steps; the identifiable scores of every group
    stay in memory for the prior counts."""

    def __init__(self, parked: Parked) -> None:
        self.parked = parked
        self.refs: dict[int, Refinement] = {}
        self.q: dict[int, OffsetScores] = {}
        self.versions: dict[int, int] = {}

    def add(self, group: int, ref: Refinement) -> None:
        """Take the refinement of vessel group ``group`` (its parts are parked)."""
        self.refs[group] = ref
        self.q[group] = ident_scores(ref)
        self._park(group, ref)

    def _park(self, group: int, ref: Refinement) -> None:
        changed = self.versions.get(group) != ref.version
        for name in Refinement.PARTS:
            if name not in ref.__dict__:
                continue  # parked and not used by the step
            value = ref.__dict__.pop(name)
            key = f"g{group}.{name}"
            if key not in self.parked or (changed and name in Refinement.STATE):
                self.parked.put(key, value)
        self.versions[group] = ref.version
        ref.load_part = functools.partial(_load_part, self.parked, group)

    def each(self, f: Callable[[Refinement], Any]) -> list[Any]:
        out = []
        for group, ref in self.refs.items():
            out.append(f(ref))
            if self.versions[group] != ref.version:
                self.q[group] = ident_scores(ref)
            self._park(group, ref)
        return out

    def counts(self, prior: NDArray[np.float64]) -> NDArray[np.int64]:
        total = np.zeros(prior.size, dtype=np.int64)
        for sc in self.q.values():
            total += prior_counts(sc, prior)
        return total

    def n_ident(self) -> int:
        return sum(sc.rows.size for sc in self.q.values())

    def pop(self, group: int) -> Refinement:
        """The refinement of ``group``, its parts loaded on use (and then no longer
        parked: call after the last step)."""
        ref = self.refs.pop(group)
        self.q.pop(group)
        for name in Refinement.PARTS:
            key = f"g{group}.{name}"
            if key in self.parked:
                setattr(ref, name, self.parked.pop(key))
        del ref.__dict__["load_part"]
        return ref
