"""One definition of each constant: the sky's rates are written in ``scopelink.astro.rates`` only
(Python, the dashboard's script and page included), and the docs state the values the code has."""

from __future__ import annotations

import re
from pathlib import Path

from scopelink.astro import LUNAR_RATE_DEG_S, SIDEREAL_DAY_S, SOLAR_RATE_DEG_S

ROOT = Path(__file__).resolve().parent.parent
SRC = ROOT / "src" / "scopelink"
RATES = SRC / "astro" / "rates.py"

# A rate written again: the sidereal day, or 15.041 arcsec/s, or an arcsec/s rate over 3600.
WRITTEN_AGAIN = re.compile(r"86164|15\.041|\b1[45]\.[0-9]+ */ *3600")


def test_the_sky_rates_are_written_only_in_astro_rates() -> None:
    places = [
        f"{path.relative_to(ROOT)}:{number}: {line.strip()}"
        for path in sorted(SRC.rglob("*"))
        if path.suffix in {".py", ".js", ".html"} and path != RATES
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1)
        if WRITTEN_AGAIN.search(line)
    ]
    assert places == [], "import them from scopelink.astro instead:\n" + "\n".join(places)
    assert WRITTEN_AGAIN.search(RATES.read_text(encoding="utf-8"))  # the pattern can match


def test_the_docs_state_the_rates_the_code_has() -> None:
    astronomy = (ROOT / "docs" / "astronomy.md").read_text(encoding="utf-8")
    assert f"{SIDEREAL_DAY_S} s" in astronomy
    assert f"{SOLAR_RATE_DEG_S * 3600:.1f}″/s" in astronomy
    assert f"{LUNAR_RATE_DEG_S * 3600:.3f}″/s" in astronomy


def test_the_tracking_page_states_the_rates_and_loop_settings_the_code_has() -> None:
    from scopelink.astro import KING_RATE_DEG_S
    from scopelink.drivers.synscan.identify import MAX_SYNSCAN_TRACKING_OFFSET_ARCSEC_S
    from scopelink.drivers.synscan.rates import (
        LOOP_GAIN_PER_S,
        MAX_CORRECTION_ARCSEC_S,
        POSITION_REPLY_BYTES,
    )
    from scopelink.sim.mount import MAX_SIM_TRACKING_OFFSET_ARCSEC_S
    from scopelink.sim.tracking import POLE_TRACKING_DEG

    tracking = (ROOT / "docs" / "tracking.md").read_text(encoding="utf-8")
    assert f"King {KING_RATE_DEG_S * 3600:.4f}″/s" in tracking
    assert f"`LOOP_GAIN_PER_S` = {LOOP_GAIN_PER_S:g} /s" in tracking
    assert f"`MAX_CORRECTION_ARCSEC_S` ({MAX_CORRECTION_ARCSEC_S:g}″/s)" in tracking
    assert f"its {POSITION_REPLY_BYTES}-byte reply" in tracking
    assert f"`POLE_TRACKING_DEG`, {POLE_TRACKING_DEG:g}°" in tracking
    assert MAX_SIM_TRACKING_OFFSET_ARCSEC_S == MAX_SYNSCAN_TRACKING_OFFSET_ARCSEC_S == 3600.0
    assert "3600″/s (1°/s) on each axis" in tracking
    # The SynScan alt-az loop (drivers/synscan/altaz_rates.py).
    from scopelink.drivers.synscan.altaz_rates import FEED_FORWARD_STEP_S
    from scopelink.drivers.synscan.identify import MAX_SLEW_RATE_DEG_S

    assert f"`FEED_FORWARD_STEP_S` = {FEED_FORWARD_STEP_S:g} s of the mount's clock" in tracking
    assert f"(`MAX_SLEW_RATE_DEG_S`, 800x sidereal,\n{MAX_SLEW_RATE_DEG_S:.2f}°/s)" in tracking
