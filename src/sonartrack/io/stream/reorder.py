"""Blocks put back in order: a small window of early blocks held until the one before them arrives, duplicates
dropped, and what never came named as a gap (and, if it comes after all, as late).

A recorder's blocks travel in order over one TCP connection, but a recorder with several writers, a relay, or a
reconnect that resends its last blocks delivers some twice or out of order. :class:`BlockReorderer` takes blocks
as they come and gives them out in order and contiguous:

* the next expected index ``n`` starts at the first block's first index;
* a block starting at ``n`` goes out at once, then every held block that now follows;
* a block starting after ``n`` is held; when more than ``window_blocks`` blocks are held, or the oldest held
  block has waited ``window_s`` seconds (wall clock, :meth:`BlockReorderer.expire`), the samples before the
  earliest held block are declared lost: ``StreamEvent("gap", n, count)``, and the held blocks go out;
* a block that ends at or before ``n`` was either given out already (``duplicate``, dropped) or lies in a
  declared gap (``late``, dropped: the samples after it have gone out); one that straddles ``n`` has its known
  head cut (``overlap``) and its new tail given out.

Memory: at most ``window_blocks`` blocks and the starts of the last :data:`RECENT` blocks given out.
"""

from __future__ import annotations

import time
from collections import deque

from sonartrack.io.stream.types import SampleBlock, StreamEvent

#: starts of blocks given out that are remembered to tell a duplicate from a late block
RECENT = 4096


class BlockReorderer:
    """In-order, contiguous blocks from blocks as they arrive (module doc)."""

    def __init__(self, window_blocks: int = 8, window_s: float = 1.0, clock=time.monotonic):
        self.window_blocks = int(window_blocks)
        self.window_s = float(window_s)
        self.next_index: int | None = None
        self._held: dict[int, tuple[SampleBlock, float]] = {}
        self._given: deque[int] = deque(maxlen=RECENT)
        self._given_set: set[int] = set()
        self._clock = clock

    @property
    def held(self) -> int:
        """Blocks held waiting for an earlier one."""
        return len(self._held)

    def push(self, block: SampleBlock) -> list:
        """Take one block as it arrived; what may now be given out.

        Parameters
        ----------
        block : SampleBlock
            A block of the stream (any order).

        Returns
        -------
        list
            SampleBlock | StreamEvent in order: a gap event before the block after it.
        """
        first, n = block.first_index, block.samples.shape[0]
        if self.next_index is None:
            self.next_index = first
        nxt = self.next_index
        if first + n <= nxt:
            kind = "duplicate" if first in self._given_set else "late"
            why = "already received: dropped" if kind == "duplicate" else "arrived after its samples were declared lost"
            return [StreamEvent(kind, f"block of {n} samples at index {first} {why}", first, n)]
        if first < nxt:
            cut = nxt - first
            out = [StreamEvent("overlap", f"block at index {first} repeats {cut} samples already received: their "
                                          "copy dropped", first, cut)]
            return out + self._give(SampleBlock(nxt, block.samples[cut:]))
        if first == nxt:
            return self._give(block)
        if first in self._held:
            return [StreamEvent("duplicate", f"block of {n} samples at index {first} already held: dropped", first, n)]
        self._held[first] = (block, self._clock())
        return self._over_window()

    def expire(self) -> list:
        """Declare the gap before the held blocks when the oldest has waited ``window_s`` (call it now and then).

        Returns
        -------
        list
            A gap event and the held blocks, or nothing.
        """
        if self._held and self._clock() - min(t for _, t in self._held.values()) >= self.window_s:
            return self._skip_to_held()
        return []

    def drain(self) -> list:
        """The end of the stream: every held block given out, gaps before them declared.

        Returns
        -------
        list
            Gap events and blocks in order.
        """
        out = []
        while self._held:
            out += self._skip_to_held()
        return out

    def _over_window(self) -> list:
        return self._skip_to_held() if len(self._held) > self.window_blocks else []

    def _skip_to_held(self) -> list:
        first = min(self._held)
        count = first - self.next_index
        gap = StreamEvent("gap", f"{count} samples at index {self.next_index} never arrived: skipped",
                          self.next_index, count)
        self.next_index = first
        return [gap, *self._give(self._held.pop(first)[0])]

    def _give(self, block: SampleBlock) -> list:
        out = []
        while True:
            out.append(block)
            if len(self._given) == self._given.maxlen:
                self._given_set.discard(self._given[0])
            self._given.append(block.first_index)
            self._given_set.add(block.first_index)
            self.next_index = block.first_index + block.samples.shape[0]
            entry = self._held.pop(self.next_index, None)
            if entry is None:
                return out + self._straddling()
            block = entry[0]

    def _straddling(self) -> list:
        """Held blocks the given-out ones now cover (in part): cut or dropped as :meth:`push` would."""
        out = []
        for first in sorted(k for k in self._held if k < self.next_index):
            out += self.push(self._held.pop(first)[0])
        return out
