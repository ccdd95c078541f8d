"use strict";
// The direction pad, its speeds and the keyboard (docs/dashboard.md, "Controls"). Uses app.js's
// $, api, view and showMessage. What each arrow moves comes from the server with every state
// (state.pad: N/S/E/W on an equatorial mount, following the pier side; Up/Down/Left/Right on an
// alt-az one); the speeds are the hand control's (mount.rates).
//
// A direction moves while anything holds it (a pointer, a key, the gamepad): every holder must
// let go before it stops, and opposite directions cancel. Each axis sends its moves one at a
// time, in order, so a release can never overtake the press before it.

const Motion = (() => {
  const DIRECTIONS = ["up", "down", "left", "right"];
  const KEYS = {
    ArrowUp: "up", ArrowDown: "down", ArrowLeft: "left", ArrowRight: "right",
    w: "up", s: "down", a: "left", d: "right", W: "up", S: "down", A: "left", D: "right",
  };
  const holders = { up: new Set(), down: new Set(), left: new Set(), right: new Set() };
  const sent = { primary: 0, secondary: 0 };
  const queues = { primary: Promise.resolve(), secondary: Promise.resolve() };
  let pad = null; // state.pad
  let lastTracking = null;

  function speed() {
    const option = $("rate").selectedOptions[0];
    return option ? Number(option.dataset.rate) : 0;
  }

  function wanted(axis) {
    if (!pad) return 0;
    let rate = 0;
    for (const dir of DIRECTIONS) {
      if (holders[dir].size && pad[dir].axis === axis) rate += pad[dir].sign * speed();
    }
    return rate;
  }

  // Send what the holders want now, after whatever this axis sent before.
  function apply(axis) {
    queues[axis] = queues[axis].then(async () => {
      const rate = wanted(axis);
      if (rate === sent[axis]) return;
      const reply = await api("/api/move", { axis, rate_deg_s: rate, session: view.session });
      if (reply) { sent[axis] = rate; return; }
      if (rate === 0) return; // the error is shown; the next change tries again
      // Refused (a limit, parked...): nothing holds on, and a motion the axis had before (a
      // speed change refused) is stopped rather than left running.
      for (const dir of DIRECTIONS) if (pad && pad[dir].axis === axis) holders[dir].clear();
      showButtons();
      if (sent[axis] !== 0 && (await api("/api/move", { axis, rate_deg_s: 0, session: view.session }))) {
        sent[axis] = 0;
      }
    });
    return queues[axis];
  }

  function showButtons() {
    for (const button of document.querySelectorAll("#pad button[data-dir]")) {
      button.classList.toggle("held", holders[button.dataset.dir].size > 0);
    }
  }

  function hold(dir, source) {
    if (!pad || document.body.dataset.readOnly === "true") return Promise.resolve();
    holders[dir].add(source);
    showButtons();
    return apply(pad[dir].axis);
  }

  function release(dir, source) {
    if (!holders[dir].delete(source)) return Promise.resolve();
    showButtons();
    return pad ? apply(pad[dir].axis) : Promise.resolve();
  }

  function releaseAll(source) {
    for (const dir of DIRECTIONS) release(dir, source);
  }

  // STOP: every holder lets go, and the mount aborts everything (goto, moves, not tracking).
  async function stop() {
    for (const dir of DIRECTIONS) holders[dir].clear();
    showButtons();
    sent.primary = sent.secondary = 0;
    const reply = await api("/api/abort");
    if (reply) showMessage("stopped", "info");
  }

  function renderPad(state) {
    if (!state.pad) return; // keep the last mapping: a release must still find its axis
    pad = state.pad;
    for (const button of document.querySelectorAll("#pad button[data-dir]")) {
      const dir = pad[button.dataset.dir];
      const label = button.querySelector(".dir");
      if (label.textContent !== dir.label) label.textContent = dir.label;
      button.title = `${dir.title} (hold)`;
      button.setAttribute("aria-label", dir.title);
    }
  }

  // The tracking menu shows what the mount reports, at start and after every change.
  function renderTracking(state) {
    if (!state.connected || state.tracking === lastTracking) return;
    const select = $("tracking-mode");
    if (document.activeElement === select) return; // the observer is choosing
    lastTracking = state.tracking;
    if (![...select.options].some((o) => o.value === state.tracking)) {
      const option = document.createElement("option");
      option.value = option.textContent = state.tracking;
      select.append(option);
    }
    select.value = state.tracking;
  }

  function renderRates(mount) {
    const select = $("rate");
    const rates = mount.rates;
    const current = select.value;
    const options = rates.choices.map((choice) => {
      const option = document.createElement("option");
      option.value = choice.key;
      option.textContent = choice.label;
      option.dataset.rate = String(choice.rate_deg_s);
      return option;
    });
    select.replaceChildren(...options);
    select.value = rates.choices.some((c) => c.key === current) ? current : rates.default;
  }

  const typing = (event) => {
    const target = event.target;
    return Boolean(target && (["INPUT", "SELECT", "TEXTAREA"].includes(target.tagName) || target.isContentEditable));
  };

  function toggleHelp(show) {
    const help = $("keys-help");
    help.hidden = show === undefined ? !help.hidden : !show;
    if (!help.hidden) $("keys-close").focus();
  }

  function setupKeys() {
    document.addEventListener("keydown", (event) => {
      if (typing(event) || event.ctrlKey || event.metaKey || event.altKey) return;
      if (event.key === " " || event.key === "Escape") {
        event.preventDefault();
        if (event.key === "Escape" && !$("keys-help").hidden) toggleHelp(false);
        if (!event.repeat) stop();
        return;
      }
      if (event.key === "?") { event.preventDefault(); toggleHelp(); return; }
      const dir = KEYS[event.key];
      if (dir) { event.preventDefault(); if (!event.repeat) hold(dir, `key ${event.key.toLowerCase()}`); }
    });
    // Releases are heard in the capture phase: no other handler (the chart's keys) can swallow
    // the keyup that stops a motion.
    window.addEventListener("keyup", (event) => {
      const dir = KEYS[event.key];
      if (!dir) return;
      release(dir, `key ${event.key.toLowerCase()}`); // "w" and "W" (Shift) are one key
    }, true);
    // A key released while the window had no focus never sends keyup: stop on losing focus,
    // and on the page being hidden (a locked phone, another tab) even where no blur comes.
    const letGo = () => {
      for (const dir of DIRECTIONS) for (const source of [...holders[dir]]) {
        if (source.startsWith("key") || source === "pointer") release(dir, source);
      }
    };
    window.addEventListener("blur", letGo);
    document.addEventListener("visibilitychange", () => { if (document.hidden) letGo(); });
    $("keys-button").addEventListener("click", () => toggleHelp());
    $("keys-close").addEventListener("click", () => toggleHelp(false));
  }

  function setupPointer() {
    for (const button of document.querySelectorAll("#pad button[data-dir]")) {
      const dir = button.dataset.dir;
      button.addEventListener("pointerdown", (event) => {
        event.preventDefault();
        try { button.setPointerCapture(event.pointerId); } catch (_) { /* not a real pointer */ }
        hold(dir, "pointer");
      });
      for (const name of ["pointerup", "pointercancel", "lostpointercapture"]) {
        button.addEventListener(name, () => release(dir, "pointer"));
      }
      button.addEventListener("contextmenu", (event) => event.preventDefault());
    }
    $("pad-stop").addEventListener("click", stop);
  }

  function setup() {
    setupPointer();
    setupKeys();
    $("rate").addEventListener("change", () => {
      $("rate").blur(); // back to the keys: arrows on a focused menu would change the speed
      apply("primary");
      apply("secondary");
    });
    document.addEventListener("scopelink:state", (event) => {
      renderPad(event.detail);
      renderTracking(event.detail);
    });
    document.addEventListener("scopelink:link", (event) => {
      if (event.detail) return;
      // The socket closed: the server stopped this page's motions (dead-man). Nothing is held
      // any more: a key or stick still down must be pressed again once the page is back.
      for (const dir of DIRECTIONS) holders[dir].clear();
      sent.primary = sent.secondary = 0;
      showButtons();
    });
    document.addEventListener("scopelink:mount", (event) => {
      renderRates(event.detail);
      lastTracking = null; // the menu was rebuilt: show the real mode again
      if (view.state) renderTracking(view.state);
    });
  }

  return { setup, hold, release, releaseAll, stop, directions: DIRECTIONS };
})();
