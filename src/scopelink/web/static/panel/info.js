"use strict";
// The information the server computes, in words (docs/dashboard.md): the clock strip, slew
// progress and how it ended (in the top bar, beside STOP), the health of the link, the selected
// object's almanac, the traffic panel's folding. Uses app.js's $, setText, fmtDeg, fmtAngle,
// showMessage and view.

const Info = (() => {
  const pad2 = (n) => String(n).padStart(2, "0");

  function hms(hours) {
    let seconds = Math.round(((hours % 24) + 24) % 24 * 3600) % 86400;
    const h = Math.floor(seconds / 3600); seconds -= h * 3600;
    const m = Math.floor(seconds / 60);
    return `${pad2(h)}:${pad2(m)}:${pad2(seconds - m * 60)}`;
  }

  function duration(seconds) {
    const s = Math.max(0, Math.round(seconds));
    if (s < 60) return `${s} s`;
    const m = Math.floor(s / 60);
    if (m < 60) return `${m} min ${pad2(s % 60)} s`;
    return `${Math.floor(m / 60)} h ${pad2(m % 60)} min`;
  }

  // A time of the mount's clock as local time of this device, and how far from the mount's
  // clock now (the last update's: the countdown runs with the updates, nothing is polled).
  let mountNow = null;
  function when(iso) {
    if (!iso) return "—";
    const t = new Date(iso);
    const clock = t.toLocaleTimeString([], { hour: "2-digit", minute: "2-digit", hour12: false });
    if (!mountNow) return clock;
    const minutes = (t - mountNow) / 60000;
    const rel = minutes >= 0 ? `in ${duration(minutes * 60)}` : `${duration(-minutes * 60)} ago`;
    return `${clock} (${rel})`;
  }

  function renderClock(clock) {
    if (!clock) return;
    const utc = new Date(clock.utc);
    mountNow = utc;
    setText("ck-utc", `${utc.toISOString().slice(0, 10)} ${utc.toISOString().slice(11, 19)}`);
    const zone = Intl.DateTimeFormat().resolvedOptions().timeZone || "this device";
    setText("ck-local", `${utc.toLocaleTimeString([], { hour12: false })} (${zone})`);
    setText("ck-lst", hms(clock.lst_hours));
    const alt = (a) => (a == null ? "—" : `${a >= 0 ? "+" : "−"}${Math.abs(a).toFixed(1)}°`);
    setText("ck-sun-moon", `Sun ${alt(clock.sun_alt)}, Moon ${alt(clock.moon_alt)}`);
    setText("ck-twilight", clock.twilight || "—");
    $("ck-twilight").dataset.phase = clock.twilight || "";
  }

  function renderSlew(slew) {
    const line = $("slew-status");
    let text = "";
    let kind = "";
    if (slew && slew.active) {
      kind = "active";
      if (slew.kind === "park") text = "parking…";
      else if (slew.kind === "moving") text = "moving";
      else {
        text = `slewing to ${slew.target}`;
        if (slew.distance_deg != null) text += `: ${slew.distance_deg.toFixed(1)}° to go`;
        if (slew.eta_s != null && slew.eta_s > 0) text += `, about ${duration(slew.eta_s)}`;
      }
    } else if (slew) {
      kind = slew.arrived ? "arrived" : "stopped";
      if (slew.kind === "park") text = "parked";
      else if (slew.kind === "moving") text = "stopped";
      else if (slew.arrived) text = `arrived at ${slew.target}`;
      else text = `stopped ${slew.distance_deg == null ? "" : `${slew.distance_deg.toFixed(1)}° `}short of ${slew.target}`;
    }
    setText("slew-status", text);
    line.dataset.kind = kind;
    line.hidden = !text;
    // The goto's own "slewing to ..." toast must not outlive the slew it announced.
    const toast = $("message");
    if (kind && kind !== "active" && !toast.hidden && toast.className === "info"
        && toast.textContent.startsWith("slewing to ")) toast.hidden = true;
  }

  function renderHealth(state) {
    const words = state.health_words;
    if (words) {
      setText("hl-words", words.text);
      $("hl-words").dataset.level = words.level;
    }
    const problems = $("hl-problems-line");
    setText("hl-problems-line", state.problems.length ? state.problems.join("; ") : "");
    problems.hidden = !state.problems.length;
  }

  // --- the selected object (or, with nothing selected, the goto target)

  const REFETCH_MIN_MS = 10000;
  let fetchedAt = 0;
  // An event of the shown almanac is past: fetch the next ones (once per event, not a poll).
  function passed(info) {
    const times = [info.rise, info.transit, info.set, info.limit && info.limit.at];
    return times.some((iso) => iso && mountNow && new Date(iso) < mountNow);
  }

  let shownName = null;
  let shownInfo = null;
  let infoSerial = 0;

  function objectName() {
    const sel = view.selected;
    if (sel && sel.name) return sel.name;
    if (sel) return null; // a point of the sky: no almanac
    const target = view.state && view.state.target;
    return target && target.name ? target.name : null;
  }

  async function refreshObject(force) {
    const name = objectName();
    if (name === shownName && !force) return;
    shownName = name;
    const serial = ++infoSerial;
    fetchedAt = Date.now();
    $("object-info").hidden = true; // until the new object's almanac has come
    shownInfo = null;
    if (!name) return;
    let info;
    try {
      const response = await fetch(`/api/object?name=${encodeURIComponent(name)}`);
      info = await response.json();
      if (!response.ok) {
        if (serial !== infoSerial) return;
        $("object-info").hidden = true;
        // Busy (429): ask again at an update after the server's Retry-After second.
        if (response.status === 429) setTimeout(() => { if (serial === infoSerial) shownName = null; }, 1000);
        return;
      }
    } catch (_) { return; }
    if (serial !== infoSerial) return;
    shownInfo = info;
    renderObject(info);
    $("object-info").hidden = false;
  }

  function renderObject(info) {
    setText("oi-title", info.name);
    setText("oi-type", [info.type, info.constellation && `in ${info.constellation}`].filter(Boolean).join(" "));
    const parts = [];
    parts.push(info.magnitude == null ? "magnitude —" : `magnitude ${info.magnitude.toFixed(1)}`);
    if (info.size_arcmin) {
      const [major, minor] = info.size_arcmin;
      parts.push(minor ? `${major.toFixed(1)}′ × ${minor.toFixed(1)}′` : `${major.toFixed(1)}′`);
    }
    setText("oi-mag", parts.join(", "));
    let rts;
    if (info.always_up) rts = `never sets; transit ${when(info.transit)}`;
    else if (info.never_up) rts = "does not rise in the next 24 h";
    else rts = `rises ${when(info.rise)}, transits ${when(info.transit)}, sets ${when(info.set)}`;
    setText("oi-rts", rts);
    setText("oi-limit", info.limit
      ? `${info.limit.event === "sets" ? "sinks below" : "rises above"} it ${when(info.limit.at)}`
      : (info.alt_deg > 0 ? "stays above it for 24 h" : "stays below it for 24 h"));
    $("oi-meridian").parentElement.hidden = false;
    setText("oi-meridian", info.meridian_limit ? `reached ${when(info.meridian_limit)} (tube on the west side)` : "none (not a German mount)");
  }

  // --- traffic: folded by default; a mount without a wire says so in one line

  function renderTraffic(mount) {
    const rows = $("traffic").tBodies[0].rows.length;
    const noWire = mount.identity.protocol === "simulator";
    $("traffic-nowire").hidden = !(noWire && rows === 0);
    $("traffic-panel").hidden = noWire && rows === 0;
  }

  // --- a device without motors (Sky Commander): the push-to view comes first

  function renderMotors(mount) {
    const caps = mount.capabilities;
    const motors = caps.can_goto || caps.can_move_axis.some(Boolean);
    document.body.dataset.motors = String(motors);
  }

  function setup() {
    document.addEventListener("scopelink:state", (event) => {
      const state = event.detail;
      renderClock(state.clock);
      renderSlew(state.slew);
      renderHealth(state);
      refreshObject(false);
      if (shownInfo && state.clock) {
        renderObject(shownInfo); // the countdowns run with the updates
        if (passed(shownInfo) && Date.now() - fetchedAt > REFETCH_MIN_MS) refreshObject(true);
      }
    });
    document.addEventListener("scopelink:mount", (event) => {
      renderTraffic(event.detail);
      renderMotors(event.detail);
    });
    // The chart's selection shows in #selection-name (app.js): follow it from there.
    new MutationObserver(() => refreshObject(false)).observe($("selection"), {
      subtree: true, childList: true, characterData: true, attributes: true,
    });
  }

  return { setup, refreshObject };
})();

document.addEventListener("DOMContentLoaded", Info.setup);
