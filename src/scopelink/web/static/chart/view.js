// Where the chart looks and how the observer moves it: the view centre (altitude, azimuth) and
// the field across the canvas (FOV_MIN to FOV_MAX degrees); mouse wheel and drag, touch drag and
// pinch, keys on the focused chart (+/− zoom, arrows pan, 0 whole sky, M centre on the mount),
// and the buttons and field-size inputs under the chart. A click that did not drag selects.
"use strict";

export const FOV_MIN = 1; // degrees across the canvas at full zoom
export const FOV_MAX = 200; // the whole sky down to 10° below the horizon
const WHOLE_SKY = { alt: 90, az: 180, fov: FOV_MAX }; // zenith at the centre, north up
const CLICK_SLOP_PX = 6; // a press that moves less than this is a click, not a drag
const FIELD_KEY = "scopelink.chart.field";
export const DEFAULT_FIELD = { width: 0.7, height: null }; // an eyepiece's round field, degrees

// follow: keep the mount at the centre (set by "Mount", ended by any pan or "Sky").
export const view = { ...WHOLE_SKY, follow: false };

const clamp = (v, lo, hi) => Math.min(hi, Math.max(lo, v));

export function loadField() {
  try {
    const stored = JSON.parse(localStorage.getItem(FIELD_KEY) || "null");
    if (stored && stored.width > 0 && stored.width <= 10 && (stored.height == null || (stored.height > 0 && stored.height <= 10))) {
      return { width: stored.width, height: stored.height || null };
    }
  } catch (_) { /* private mode or bad JSON: the default */ }
  return { ...DEFAULT_FIELD };
}

function saveField(field) {
  try { localStorage.setItem(FIELD_KEY, JSON.stringify(field)); } catch (_) { /* private mode */ }
}

// chart: {canvas, redraw(), scene(), select(x, y), mountAltAz()}.
export function attachControls(chart) {
  const canvas = chart.canvas;
  const pointers = new Map();
  let gesture = null;

  const degPerPx = () => 1 / chart.scene().pxPerDeg;
  function pan(dx, dy) {
    view.follow = false;
    view.az = (view.az - (dx * degPerPx()) / Math.max(Math.cos((view.alt * Math.PI) / 180), 0.2) + 360) % 360;
    view.alt = clamp(view.alt + dy * degPerPx(), -30, 90);
    chart.redraw();
  }
  function zoom(factor, x, y) {
    const before = x == null ? null : chart.scene().projection.invert([x, y]);
    view.fov = clamp(view.fov * factor, FOV_MIN, FOV_MAX);
    if (before) {
      const after = chart.scene().projection.invert([x, y]);
      if (after) {
        view.az = (view.az - (before[0] - after[0]) + 360) % 360;
        view.alt = clamp(view.alt + (before[1] - after[1]), -30, 90);
      }
    }
    chart.redraw();
  }
  function reset() { Object.assign(view, WHOLE_SKY, { follow: false }); chart.redraw(); }
  function centreOnMount() {
    view.follow = true;
    followMount(chart.mountAltAz());
    chart.redraw();
  }
  const local = (event) => {
    const rect = canvas.getBoundingClientRect();
    return [event.clientX - rect.left, event.clientY - rect.top];
  };

  canvas.addEventListener("pointerdown", (event) => {
    pointers.set(event.pointerId, local(event));
    try { canvas.setPointerCapture(event.pointerId); } catch (_) { /* synthetic */ }
    if (pointers.size === 1) {
      gesture = { kind: "drag", start: local(event), last: local(event), moved: 0 };
    } else if (pointers.size === 2) {
      const [a, b] = [...pointers.values()];
      gesture = { kind: "pinch", distance: Math.hypot(a[0] - b[0], a[1] - b[1]) || 1, fov: view.fov, moved: 99 };
    }
  });
  canvas.addEventListener("pointermove", (event) => {
    if (!pointers.has(event.pointerId) || !gesture) return;
    pointers.set(event.pointerId, local(event));
    if (gesture.kind === "drag") {
      const [x, y] = local(event);
      gesture.moved = Math.max(gesture.moved, Math.hypot(x - gesture.start[0], y - gesture.start[1]));
      if (gesture.moved >= CLICK_SLOP_PX) pan(x - gesture.last[0], y - gesture.last[1]);
      gesture.last = [x, y];
    } else if (pointers.size === 2) {
      const [a, b] = [...pointers.values()];
      const distance = Math.hypot(a[0] - b[0], a[1] - b[1]) || 1;
      view.fov = clamp((gesture.fov * gesture.distance) / distance, FOV_MIN, FOV_MAX);
      chart.redraw();
    }
  });
  const release = (event) => {
    if (!pointers.has(event.pointerId)) return;
    pointers.delete(event.pointerId);
    if (gesture && gesture.kind === "drag" && gesture.moved < CLICK_SLOP_PX && event.type === "pointerup") {
      const [x, y] = local(event);
      chart.select(x, y);
    }
    if (pointers.size === 0) gesture = null;
    else if (gesture && gesture.kind === "pinch") gesture = { kind: "drag", start: [0, 0], last: [...pointers.values()][0], moved: 99 };
  };
  canvas.addEventListener("pointerup", release);
  canvas.addEventListener("pointercancel", release);
  canvas.addEventListener("wheel", (event) => {
    event.preventDefault();
    const [x, y] = local(event);
    zoom(Math.exp(clamp(event.deltaY, -300, 300) * 0.0015), x, y);
  }, { passive: false });

  // Keys act on the chart only while it has the focus, and go no further: the arrows must not
  // also reach the page's direction pad and move the mount.
  canvas.tabIndex = 0;
  const keys = {
    "+": () => zoom(1 / 1.5), "=": () => zoom(1 / 1.5), "-": () => zoom(1.5), "−": () => zoom(1.5), _: () => zoom(1.5),
    ArrowLeft: () => pan(canvas.clientWidth / 10, 0), ArrowRight: () => pan(-canvas.clientWidth / 10, 0),
    ArrowUp: () => pan(0, canvas.clientHeight / 10), ArrowDown: () => pan(0, -canvas.clientHeight / 10),
    0: reset, Home: reset, m: centreOnMount, M: centreOnMount,
  };
  canvas.addEventListener("keydown", (event) => {
    const action = keys[event.key];
    if (!action || event.ctrlKey || event.metaKey || event.altKey) return;
    event.preventDefault();
    event.stopPropagation();
    action();
  });
  canvas.addEventListener("keyup", (event) => { if (keys[event.key]) event.stopPropagation(); });

  return { zoom, pan, reset, centreOnMount };
}

// While following, the view's centre is where the mount points (called on every state); it
// moves once the mount is `minDeg` away, so that a tracking mount redraws the sky now and
// then, not at every update.
export function followMount(where, minDeg = 0) {
  if (!view.follow || !where) return;
  const d = d3.geoDistance([-view.az, view.alt], [-where.az, where.alt]) * (180 / Math.PI);
  if (d < minDeg) return;
  view.alt = clamp(where.alt, -30, 90); view.az = where.az;
}

function button(text, label, onClick) {
  const b = document.createElement("button");
  b.type = "button"; b.textContent = text; b.setAttribute("aria-label", label); b.title = label;
  b.addEventListener("click", onClick);
  return b;
}

function numberInput(id, label, value) {
  const input = document.createElement("input");
  input.type = "number"; input.id = id; input.min = "0.05"; input.max = "10"; input.step = "0.05";
  input.setAttribute("aria-label", label); input.title = label;
  if (value != null) input.value = String(value);
  return input;
}

// The tool bar under the chart; `field` is changed in place and saved.
export function buildToolbar(canvas, actions, field, changed) {
  const bar = document.createElement("div");
  bar.className = "chart-tools";
  const fov = document.createElement("span");
  fov.className = "chart-fov";
  const width = numberInput("chart-field-width", "Field width (°)", field.width);
  const height = numberInput("chart-field-height", "Field height (°): empty for a round eyepiece field", field.height);
  height.placeholder = "round";
  const onField = () => {
    const w = Number(width.value), h = height.value === "" ? null : Number(height.value);
    if (!(w > 0 && w <= 10) || (h != null && !(h > 0 && h <= 10))) return; // kept until valid
    field.width = w; field.height = h;
    saveField(field);
    changed();
  };
  width.addEventListener("change", onField);
  height.addEventListener("change", onField);
  const fieldLabel = document.createElement("label");
  fieldLabel.className = "chart-field";
  fieldLabel.append("Field", width, "×", height, "°");
  bar.append(
    button("−", "Zoom out (−)", () => actions.zoom(1.5)),
    button("+", "Zoom in (+)", () => actions.zoom(1 / 1.5)),
    button("Sky", "Whole sky (0)", actions.reset),
    button("Mount", "Centre on the mount and follow it (M)", actions.centreOnMount),
    fov, fieldLabel,
  );
  canvas.after(bar);
  return (text) => { if (fov.textContent !== text) fov.textContent = text; };
}
