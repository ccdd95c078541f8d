"use strict";
// A gamepad through the browser's Gamepad API (docs/dashboard.md, "Controls"). The left stick
// (past a dead zone) or the d-pad holds the pad's directions through Motion, so the same mapping
// and speeds apply; any face button (A, B, X, Y) is STOP. Dead-man: centring the stick or
// letting go of the d-pad releases the direction, and losing the gamepad (unplugged, the
// browser stops reporting it, the page hidden) releases everything; so do losing the window's
// focus and losing the link. After any of these, and after STOP, nothing moves again until the
// stick has come back to the centre.

const Gamepads = (() => {
  const DEAD_ZONE = 0.3; // of full deflection: a resting stick drifts up to ~0.1-0.2
  const POLL_MS = 50;
  const STOP_BUTTONS = [0, 1, 2, 3];
  const DPAD = { up: 12, down: 13, left: 14, right: 15 };
  const held = { up: false, down: false, left: false, right: false };
  let timer = null;
  let present = false;
  let stopDown = false;
  let latched = false; // STOP was pressed: wait for the stick to centre

  function pads() {
    let list = [];
    try { list = navigator.getGamepads ? Array.from(navigator.getGamepads() || []) : []; } catch (_) { list = []; }
    return list.filter((pad) => pad && pad.connected !== false);
  }

  function setHeld(dir, on) {
    if (held[dir] === on) return;
    held[dir] = on;
    if (on) Motion.hold(dir, "gamepad"); else Motion.release(dir, "gamepad");
  }

  function releaseAll() {
    for (const dir of Object.keys(held)) setHeld(dir, false);
  }

  function status(text) {
    const line = $("gamepad-status");
    line.hidden = !text;
    if (line.textContent !== text) line.textContent = text;
  }

  function lose(why) {
    present = false;
    const moving = Object.values(held).some(Boolean);
    releaseAll();
    status("");
    if (moving) showMessage(`gamepad ${why}: stopped`, "info");
  }

  function poll() {
    const list = pads();
    if (!list.length) {
      if (present) lose("lost");
      stopPolling();
      return;
    }
    const pad = list[0];
    if (!present) { present = true; status(`gamepad: ${pad.id || "connected"} (stick moves, A/B/X/Y stops)`); }
    const buttons = pad.buttons || [];
    const axes = pad.axes || [];
    const pressed = (index) => {
      const button = buttons[index];
      return Boolean(button && (button.pressed || button.value > 0.5));
    };
    const stopNow = STOP_BUTTONS.some(pressed);
    if (stopNow && !stopDown) { releaseAll(); latched = true; Motion.stop(); }
    stopDown = stopNow;
    const x = Number(axes[0]) || 0;
    const y = Number(axes[1]) || 0;
    const want = {
      up: y < -DEAD_ZONE || pressed(DPAD.up),
      down: y > DEAD_ZONE || pressed(DPAD.down),
      left: x < -DEAD_ZONE || pressed(DPAD.left),
      right: x > DEAD_ZONE || pressed(DPAD.right),
    };
    const any = Object.values(want).some(Boolean);
    if (document.hidden) latched = true; // nothing moves from a page nobody sees
    if (stopNow || latched) {
      if (!any && !stopNow) latched = false;
      releaseAll();
      return;
    }
    for (const dir of Object.keys(want)) setHeld(dir, want[dir]);
  }

  function startPolling() {
    if (timer === null) timer = setInterval(poll, POLL_MS);
    poll();
  }

  function stopPolling() {
    if (timer !== null) { clearInterval(timer); timer = null; }
  }

  function setup() {
    window.addEventListener("gamepadconnected", startPolling);
    window.addEventListener("gamepaddisconnected", () => { if (present) poll(); });
    // An unfocused page may get a frozen snapshot of the pad: let go, and wait for the stick to
    // come back to the centre (as after STOP) before moving again. The same when the link drops,
    // and when the page is hidden: the poll runs on (slower) and would press the held stick again.
    const letGo = () => { if (present) { releaseAll(); latched = true; } };
    document.addEventListener("visibilitychange", () => {
      if (document.hidden && present) { lose("hidden"); latched = true; }
    });
    window.addEventListener("blur", letGo);
    document.addEventListener("scopelink:link", (event) => { if (!event.detail) letGo(); });
    if (pads().length) startPolling();
  }

  return { setup, poll };
})();
