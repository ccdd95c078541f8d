"""Pointing accuracy (issue #15 part 1): gotos on a misaligned sky before and after a pointing
model fitted to six syncs (docs/pointing.md).

The real SynScan emulator over TCP in front of the simulated mount, whose sky is misaligned
(``scopelink.sim.misalignment``: axis zero points and polar axis / base errors); the SynScan
driver keeps each sync on the PC. For each case: gotos to 20 stars spread over the sky with no
model (the error a user sees today), then six stars centred and synced on, then gotos to 20
other stars. Errors are where the simulated tube truly points, from the star, in arcminutes.

    .venv/bin/python -m bench.pointing            # 2 mounts x 4 misalignments
    .venv/bin/python -m bench.pointing --quick    # 1 case (the smoke test)
"""

from __future__ import annotations

import argparse
import asyncio
import random
import time

from tests.support.pointing import FIVE_DEGREES, goto_error_arcmin, rms, stars, sync_on
from tests.support.synscan_driver import START, rig

from bench.provenance import print_provenance
from scopelink.servers.synscan import SynScanConfig
from scopelink.sim import AZ_GTI, EQ6, MountModel
from scopelink.sim.misalignment import Misalignment

GOAL_RMS_ARCMIN = 2.0
SYNCS = 6
GOTOS = 20


def misalignments(count: int, seed: int = 15) -> list[Misalignment]:
    """FIVE_DEGREES, then random ones with each error up to ±2.5° (at most ~5° in all)."""
    chosen = random.Random(seed)
    found = [FIVE_DEGREES]
    while len(found) < count:
        found.append(Misalignment(*(chosen.uniform(-2.5, 2.5) for _ in range(4))))
    return found


async def one_case(model: MountModel, misalignment: Misalignment) -> tuple[float, ...]:
    config = SynScanConfig(model=165) if model is AZ_GTI else None
    async with rig("tcp", model=model, config=config) as r:
        r.sim.misalignment = misalignment
        targets = stars(r.mount.site, START, GOTOS, offset=0.5)
        before = [await goto_error_arcmin(r.mount, r.sim, ra, dec) for ra, dec in targets]
        started = time.perf_counter()
        for ra, dec in stars(r.mount.site, START, SYNCS, offset=0.0):
            await sync_on(r.mount, r.sim, ra, dec)
        syncing_s = time.perf_counter() - started
        fit_rms = r.mount.pointing.summary()["rms_arcmin"]
        after = [await goto_error_arcmin(r.mount, r.sim, ra, dec) for ra, dec in targets]
    return rms(before), max(before), fit_rms, rms(after), max(after), syncing_s


async def main(quick: bool) -> bool:
    cases = (
        [(EQ6, FIVE_DEGREES)]
        if quick
        else [(model, m) for model in (EQ6, AZ_GTI) for m in misalignments(4)]
    )
    print(
        f"{'mount':<8} {'misalignment (ZP1, ZP2, PAZ, PALT °)':<38} {'no model RMS/max':>17} "
        f"{'fit RMS':>8} {'model RMS/max':>14} {'6 syncs':>8}"
    )
    worst = 0.0
    for model, misalignment in cases:
        before, before_max, fit_rms, after, after_max, syncing_s = await one_case(
            model, misalignment
        )
        worst = max(worst, after)
        m = misalignment
        text = (
            f"{m.zero_primary_deg:+.2f}, {m.zero_secondary_deg:+.2f}, "
            f"{m.polar_az_deg:+.2f}, {m.polar_alt_deg:+.2f}"
        )
        print(
            f"{model.name:<8} {text:<38} {before:>7.1f}′/{before_max:>6.1f}′   "
            f"{fit_rms:>6.2f}′ {after:>6.2f}′/{after_max:>5.2f}′ {syncing_s:>7.2f}s"
        )
    met = worst <= GOAL_RMS_ARCMIN
    verdict = "met" if met else "MISSED"
    print(
        f"goal: after {SYNCS} syncs, gotos to {GOTOS} other stars within {GOAL_RMS_ARCMIN:g}′ RMS "
        f"(worst case {worst:.2f}′): {verdict}"
    )
    return met


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="one case (the smoke test)")
    arguments = parser.parse_args()
    print_provenance()
    raise SystemExit(0 if asyncio.run(main(arguments.quick)) else 1)
