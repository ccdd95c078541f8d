"""The per-address token buckets shared by the access policy and the dashboard's live opens
(``scopelink.servers.buckets``): a scan of many addresses cannot grow memory, and an address
that comes back finds its bucket as it left it (forgetting it must not refill it)."""

from __future__ import annotations

from scopelink.servers.access import AccessControl, AccessPolicy, Refusal
from scopelink.servers.buckets import KeyedBuckets


def test_only_full_idle_buckets_are_forgotten_and_only_from_kept_on() -> None:
    buckets = KeyedBuckets(rate=1.0, burst=2, kept=3)
    drained = buckets.of("drained", 0.0)
    assert drained.reserve(0.0) == 0.0
    assert drained.reserve(0.0) == 0.0
    buckets.of("busy", 0.0)
    buckets.of("idle", 0.0)
    assert len(buckets) == 3
    buckets.of("new", 0.0, busy={"busy"})  # 3 held: the full idle one goes, not the others
    assert buckets.get("idle") is None
    assert buckets.get("busy") is not None
    assert buckets.of("drained", 0.0) is drained  # still short of tokens: kept
    assert drained.wait_for_one(0.0) == 1.0
    buckets.prune(0.5, busy={"busy"})  # 3 held again: the full idle newcomer goes
    assert buckets.get("new") is None
    assert buckets.get("busy") is not None
    assert buckets.get("drained") is drained
    buckets.prune(0.5)  # 2 held: below kept, nothing goes
    assert len(buckets) == 2
    buckets.forget_if_full("drained", 0.5)
    assert buckets.get("drained") is drained
    buckets.forget_if_full("drained", 2.0)  # refilled
    assert buckets.get("drained") is None
    for n in range(1000):  # a scan: every newcomer is full, so the table stays small
        buckets.of(f"10.0.{n // 256}.{n % 256}", 3.0)
    assert len(buckets) <= 3


def test_an_address_that_drained_its_bucket_is_not_refilled_by_a_scan_of_others() -> None:
    now = [100.0]
    control = AccessControl(
        AccessPolicy(max_connections=2, requests_per_s=1.0, burst=2, max_delay_s=0.0),
        clock=lambda: now[0],
    )
    client = control.admit("192.0.2.1")
    assert not isinstance(client, Refusal)
    assert [client.admit_request() for _ in range(3)] == [0.0, 0.0, None]
    client.release()
    for n in range(100):  # each connects, asks once, leaves
        other = control.admit(f"198.51.100.{n}")
        assert not isinstance(other, Refusal)
        assert other.admit_request() == 0.0
        other.release()
    back = control.admit("192.0.2.1")
    assert not isinstance(back, Refusal)
    assert back.admit_request() is None
    assert control.retry_after_s("192.0.2.1") == 1.0
