"""Token buckets, one per key (a client address), as the access policy (``servers/access.py``) and
the dashboard's live opens (``web/live_opens.py``) both rate requests.

A key's bucket is made full on its first request and kept while it is short of tokens, so that
coming back does not refill it; once ``kept`` buckets are held, those that have refilled (and
whose key is not busy, e.g. still connected) are forgotten before another is made, so a scan of
many addresses cannot grow memory (``docs/reliability-security.md``, "Buckets per address,
forgotten when full").
"""

from __future__ import annotations

from collections.abc import Container

__all__ = ["KeyedBuckets", "TokenBucket"]


class TokenBucket:
    """``rate`` tokens a second up to ``burst``; one token per request."""

    def __init__(self, rate: float, burst: int, now: float) -> None:
        self.rate = rate
        self.burst = float(burst)
        self._tokens = float(burst)
        self._stamp = now

    def _refill(self, now: float) -> None:
        elapsed = max(0.0, now - self._stamp)
        self._tokens = min(self.burst, self._tokens + elapsed * self.rate)
        self._stamp = now

    def reserve(self, now: float, *, max_wait_s: float = float("inf")) -> float | None:
        """Take a token; the wait until it is really available (0 now), or None (nothing taken)
        when that wait would exceed ``max_wait_s``."""
        self._refill(now)
        wait = max(0.0, (1.0 - self._tokens) / self.rate)
        if wait > max_wait_s:
            return None
        self._tokens -= 1.0
        return wait

    def wait_for_one(self, now: float) -> float:
        """How long until one token is free (for a Retry-After)."""
        self._refill(now)
        return max(0.0, (1.0 - self._tokens) / self.rate)

    def full(self, now: float) -> bool:
        self._refill(now)
        return self._tokens >= self.burst


_NONE_BUSY: frozenset[str] = frozenset()


class KeyedBuckets:
    """A :class:`TokenBucket` of ``rate`` and ``burst`` per key; from ``kept`` keys on, the full
    buckets of keys that are not busy are forgotten."""

    def __init__(self, rate: float, burst: int, kept: int) -> None:
        self.rate = rate
        self.burst = burst
        self.kept = kept
        self._buckets: dict[str, TokenBucket] = {}

    def __len__(self) -> int:
        return len(self._buckets)

    def get(self, key: str) -> TokenBucket | None:
        """``key``'s bucket if it has one (it is not made)."""
        return self._buckets.get(key)

    def of(self, key: str, now: float, *, busy: Container[str] = _NONE_BUSY) -> TokenBucket:
        """``key``'s bucket, made full when it has none (idle ones are forgotten first)."""
        bucket = self._buckets.get(key)
        if bucket is None:
            self.prune(now, busy=busy)
            bucket = self._buckets[key] = TokenBucket(self.rate, self.burst, now)
        return bucket

    def forget_if_full(self, key: str, now: float) -> None:
        """Forget ``key``'s bucket if it has refilled (its key has gone idle)."""
        bucket = self._buckets.get(key)
        if bucket is not None and bucket.full(now):
            del self._buckets[key]

    def prune(self, now: float, *, busy: Container[str] = _NONE_BUSY) -> None:
        """When ``kept`` buckets or more are held, forget the full ones whose key is not busy."""
        if len(self._buckets) < self.kept:
            return
        for key in [k for k in self._buckets if k not in busy]:
            if self._buckets[key].full(now):
                del self._buckets[key]
