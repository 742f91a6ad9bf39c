"""A bounded FIFO from Zenoh callbacks to a service's one thread: what does not fit is dropped and
counted, so a flood of messages (garbage or not) cannot grow a process without bound.

Bounded by count and by bytes; a message larger than its kind allows is dropped before it is even
copied out of Zenoh (`too_big`). Callbacks never block: they only offer.
"""

from __future__ import annotations

import queue
import threading
from collections import Counter, deque
from typing import Generic, TypeVar

T = TypeVar("T")

MAX_ITEMS = 16_384  # far above a round's events (2n + 3 for n <= 4096 robots)
MAX_BYTES = 64 << 20  # 64 MiB of payloads waiting at most


class Inbox(Generic[T]):
    """Events in arrival order; `offer` drops (and counts by kind) what would exceed the bounds:
    `max_items` and `max_bytes` in all, and `caps` (kind -> at most this many queued) by kind."""

    def __init__(
        self,
        max_items: int = MAX_ITEMS,
        max_bytes: int = MAX_BYTES,
        caps: dict[str, int] | None = None,
    ) -> None:
        self.max_items, self.max_bytes = max_items, max_bytes
        self.caps = dict(caps or {})
        self._items: deque[tuple[T, int, str]] = deque()
        self._bytes = 0
        self._queued: Counter[str] = Counter()  # kind -> events queued now
        self._ready = threading.Condition()
        self.dropped: Counter[str] = Counter()  # kind -> events dropped

    def offer(self, kind: str, item: T, size: int = 0) -> bool:
        """Queue `item` (`size` payload bytes) unless the inbox is full; False if dropped."""
        with self._ready:
            if (
                len(self._items) >= self.max_items
                or self._bytes + size > self.max_bytes
                or self._queued[kind] >= self.caps.get(kind, self.max_items)
            ):
                self.dropped[kind] += 1
                return False
            self._items.append((item, size, kind))
            self._bytes += size
            self._queued[kind] += 1
            self._ready.notify()
            return True

    def too_big(self, kind: str) -> None:
        """Count a message dropped for its size, before it was queued."""
        with self._ready:
            self.dropped[kind] += 1

    def get(self, timeout: float | None = None) -> T:
        """The oldest event, waiting up to `timeout` seconds; raises queue.Empty."""
        with self._ready:
            if not self._items and not self._ready.wait_for(lambda: bool(self._items), timeout):
                raise queue.Empty
            item, size, kind = self._items.popleft()
            self._bytes -= size
            self._queued[kind] -= 1
            return item

    def get_nowait(self) -> T:
        """The oldest event; raises queue.Empty if there is none."""
        return self.get(0.0)

    def __len__(self) -> int:
        with self._ready:
            return len(self._items)


__all__ = ["MAX_BYTES", "MAX_ITEMS", "Inbox"]
