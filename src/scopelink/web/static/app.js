// scopelink dashboard. Every piece of data from the server is put on the page with textContent
// (never innerHTML), commands go to the JSON API, live state comes over the WebSocket.
"use strict";

const $ = (id) => document.getElementById(id);

const view = {
  mount: null, // the hello's description: identity, capabilities, site, limits, sidereal rate
  twilight: null, // the hello's twilight boundaries, {phase: the Sun's altitude it ends at}
  state: null,
  selected: null, // {name} of an object, or {alt, az} of a point
  connected: false,
  session: null, // the live connection's session, sent with the pad's moves (dead-man)
};

// ---------------------------------------------------------------- messages

let messageTimer = null;
function showMessage(text, kind = "error") {
  const box = $("message");
  box.textContent = text;
  box.className = kind;
  box.hidden = false;
  clearTimeout(messageTimer);
  messageTimer = setTimeout(() => { box.hidden = true; }, kind === "error" ? 12000 : 4000);
}

// ---------------------------------------------------------------- API

async function api(path, body) {
  let response;
  try {
    response = await fetch(path, {
      method: "POST",
      headers: { "Content-Type": "application/json" },
      body: JSON.stringify(body || {}),
    });
  } catch (error) {
    showMessage(`cannot reach scopelink: ${error.message}`);
    return null;
  }
  let reply = null;
  try { reply = await response.json(); } catch (_) { reply = null; }
  if (!response.ok) {
    let text = (reply && reply.error) || `${response.status} ${response.statusText}`;
    showMessage(text);
    return null;
  }
  return reply || {};
}

// ---------------------------------------------------------------- formatting

function sexagesimal(value, unitMarks, signed, decimals) {
  const sign = value < 0 ? "−" : signed ? "+" : "";
  let v = Math.abs(value);
  const scale = 10 ** decimals;
  let total = Math.round(v * 3600 * scale);
  const whole = Math.floor(total / (3600 * scale));
  total -= whole * 3600 * scale;
  const minutes = Math.floor(total / (60 * scale));
  total -= minutes * 60 * scale;
  const seconds = (total / scale).toFixed(decimals).padStart(decimals ? 3 + decimals : 2, "0");
  return `${sign}${whole}${unitMarks[0]} ${String(minutes).padStart(2, "0")}${unitMarks[1]} ${seconds}${unitMarks[2]}`;
}
const fmtHours = (h) => (h == null ? "—" : sexagesimal(h, ["h", "m", "s"], false, 1));
const fmtDeg = (d) => (d == null ? "—" : sexagesimal(d, ["°", "′", "″"], true, 0));
const fmtAngle = (d) => (d == null ? "—" : `${d.toFixed(2)}°`);
const yesNo = (b) => (b ? "yes" : "no");

// ---------------------------------------------------------------- sun warning

function renderSunWarning() {
  const s = view.state, el = $("sun-warning");
  const sun = s && s.sun;
  let text = "";
  if (sun && !(sun.radius_deg > 0)) {
    text = "Sun avoidance is OFF (limits.sun_avoidance_deg = 0): nothing stops this mount pointing at the Sun";
  } else if (sun && sun.reaches_mount_in_min != null) {
    text = `The Sun will reach where the mount points in ${sun.reaches_mount_in_min} min: ` +
      "move or park it away from the Sun's path.";
  } else if (sun && sun.up) {
    text = `The Sun is up (altitude ${sun.alt.toFixed(0)}°, azimuth ${sun.az.toFixed(0)}°): ` +
      `gotos within ${sun.radius_deg}° of it are refused. Never look through a telescope near the Sun.`;
  }
  setText("sun-warning", text);
  el.classList.toggle("off", Boolean(sun) && (!(sun.radius_deg > 0) || sun.reaches_mount_in_min != null));
  el.hidden = !text;
}

function select(selection) {
  view.selected = selection;
  renderSelection();
  Chart.select(selection);
}

function renderSelection() {
  const sel = view.selected;
  $("selection").hidden = !sel;
  if (!sel) return;
  const where = Chart.where();
  $("selection-name").textContent = sel.name ? sel.name : "Point";
  $("selection-where").textContent = where ? `alt ${fmtAngle(where.alt)}  az ${fmtAngle(where.az)}` : "";
  $("sync-selected").hidden = !sel.name;
}

// ---------------------------------------------------------------- panels

function setText(id, text) {
  const el = $(id);
  if (el.textContent !== text) el.textContent = text;
}

function renderState() {
  const s = view.state;
  if (!s) return;
  setText("st-j2000", `${fmtHours(s.ra_j2000_hours)}  ${fmtDeg(s.dec_j2000_deg)}`);
  setText("st-jnow", `${fmtHours(s.ra_of_date_hours)}  ${fmtDeg(s.dec_of_date_deg)}`);
  setText("st-altaz", `${fmtAngle(s.alt_deg)}  ${fmtAngle(s.az_deg)}`);
  // A position older than stale_after_s (or from a lost link) is shown greyed, never as current.
  for (const id of ["st-j2000", "st-jnow", "st-altaz", "st-pier"]) $(id).classList.toggle("stale", s.stale);
  setText("st-pier", s.pier_side);
  setText("st-meridian", s.meridian ? s.meridian.text : "—");  // German mounts only
  // While the link is down nobody knows whether the mount moves: no motion state is claimed.
  setText("st-slewing", s.connected ? yesNo(s.slewing) : "unknown (link down)");
  setText("st-tracking", s.connected ? s.tracking : "unknown (link down)");
  setText("st-parked", yesNo(s.parked));
  setText("st-target", s.target ? s.target.name || targetText(s.target) : "—");
  setText("hl-connected", yesNo(s.connected));
  setText("hl-polls", `${s.health.polls} / ${s.health.failures} (watchers ${s.health.watchers})`);
  const readAt = s.read_at.replace("T", " ").replace(/\.\d+/, "").replace("+00:00", " UTC");
  setText("hl-read-at", readAt);
  setText("mount-time", `mount clock: ${readAt}`);
  const age = $("hl-age");
  setText("hl-age", s.stale ? `${s.age_s.toFixed(1)} s: stale (over ${s.stale_after_s} s), not current`
    : `${s.age_s.toFixed(1)} s`);
  age.classList.toggle("bad", s.stale);
  const problems = $("hl-problems");
  setText("hl-problems", s.problems.length ? s.problems.join("; ") : "none");
  problems.classList.toggle("bad", s.problems.length > 0);
  $("status").dataset.slewing = String(s.slewing);
  renderSunWarning();
  // The panel's scripts (static/panel/) follow the state from here.
  document.dispatchEvent(new CustomEvent("scopelink:state", { detail: s }));
}

function targetText(t) {
  if (t.ra_j2000_hours != null) return `${fmtHours(t.ra_j2000_hours)} ${fmtDeg(t.dec_j2000_deg)}`;
  return `alt ${fmtAngle(t.alt_deg)} az ${fmtAngle(t.az_deg)}`;
}

function renderMount() {
  const m = view.mount;
  if (!m) return;
  const id = m.identity;
  const name = [id.model, id.firmware && `firmware ${id.firmware}`].filter(Boolean).join(", ");
  setText("mount-name", name);
  setText("hl-identity", `${name} — ${id.protocol}${id.link ? ` on ${id.link}` : ""}`);
  const select = $("tracking-mode");
  const current = select.value;
  select.replaceChildren();
  for (const mode of m.capabilities.tracking_modes) {
    const option = document.createElement("option");
    option.value = mode; option.textContent = mode;
    select.append(option);
  }
  // The menu shows the mount's real mode (panel/motion.js keeps it so); never a guess.
  const real = view.state && view.state.connected ? view.state.tracking : current;
  if (real) select.value = real;
  const site = m.site;
  for (const [inputId, value] of [["site-lat", site.latitude_deg], ["site-lon", site.longitude_deg], ["site-elev", site.elevation_m]]) {
    const input = $(inputId);
    if (document.activeElement !== input) input.value = String(value);
  }
  document.dispatchEvent(new CustomEvent("scopelink:mount", { detail: m }));
}

const traffic = { paused: false, rows: 200 };

function appendTraffic(lines) {
  if (!lines || !lines.length || traffic.paused) return;
  const body = $("traffic").tBodies[0];
  const scroller = body.closest(".traffic-scroll");
  const atBottom = scroller.scrollTop + scroller.clientHeight >= scroller.scrollHeight - 4;
  for (const line of lines) {
    const row = document.createElement("tr");
    row.className = `from-${line.from}`;
    const time = new Date(line.at * 1000).toISOString().slice(11, 23);
    const cells = [
      ["time", time],
      ["link", line.link],
      ["dir", line.from === "pc" ? "PC →" : "← dev"],
      ["bytes", line.text],
    ];
    for (const [cls, text] of cells) {
      const cell = document.createElement("td");
      cell.className = cls; cell.textContent = text;
      if (cls === "bytes") cell.title = line.hex;
      row.append(cell);
    }
    const meaning = document.createElement("td");
    meaning.className = "meaning";
    for (const m of line.meanings) {
      const part = document.createElement("div");
      part.className = `m-${m.kind}`;
      part.textContent = m.text;
      meaning.append(part);
    }
    row.append(meaning);
    body.append(row);
  }
  while (body.rows.length > traffic.rows) body.deleteRow(0);
  $("traffic-empty").hidden = body.rows.length > 0;
  // A mount without a wire shows one line until some program talks to a server.
  $("traffic-panel").hidden = false;
  $("traffic-nowire").hidden = true;
  if (atBottom) scroller.scrollTop = scroller.scrollHeight;
}

// ---------------------------------------------------------------- live updates

let socket = null;
let retryDelay = 500;

function setLinkStatus(ok, text) {
  const badge = $("link-status");
  badge.dataset.ok = String(ok);
  badge.textContent = text;
  // The pad lets go when the link drops: the server's dead-man stopped this page's motions.
  document.dispatchEvent(new CustomEvent("scopelink:link", { detail: ok }));
}

function connect() {
  const scheme = location.protocol === "https:" ? "wss:" : "ws:";
  socket = new WebSocket(`${scheme}//${location.host}/ws`);
  socket.addEventListener("open", () => { retryDelay = 500; setLinkStatus(true, "live"); });
  socket.addEventListener("message", (event) => {
    let message;
    try { message = JSON.parse(event.data); } catch (_) { return; }
    // What the panel shows beside the state (web/view_state.py) is read as part of it.
    if (message.panel && message.state) Object.assign(message.state, message.panel);
    if (message.type === "hello") {
      view.mount = message.mount;
      view.twilight = message.twilight_deg;
      view.session = message.session; // the pad's moves name it: they stop if this page goes
      $("traffic-off").hidden = message.traffic_enabled;
      $("traffic").tBodies[0].replaceChildren();
      $("traffic-empty").hidden = !message.traffic_enabled;
      renderMount();
    }
    if (message.type === "update" && message.mount) { view.mount = message.mount; renderMount(); }
    if (message.state) { view.state = message.state; renderState(); }
    Chart.update({
      mount: view.mount, state: view.state, sky: message.sky, frame: message.sky_frame, twilight: view.twilight,
    });
    if (message.sky) renderSelection();
    appendTraffic(message.traffic);
  });
  socket.addEventListener("close", () => {
    setLinkStatus(false, "reconnecting…");
    setTimeout(connect, retryDelay);
    retryDelay = Math.min(retryDelay * 2, 10000);
  });
}

// ---------------------------------------------------------------- controls

// A read-only server refuses every command (403): grey the controls out instead of letting
// each click fail.
async function applyAccess() {
  let access;
  try { access = await (await fetch("/api/access")).json(); } catch (_) { return; }
  if (!access || access.read_only !== true) return;
  document.body.dataset.readOnly = "true";
  $("read-only-note").hidden = false;
  const controls = document.querySelectorAll(
    'section[aria-label="Controls"] :is(button, input, select), #go-selected, #sync-selected, #abort');
  for (const control of controls) control.disabled = true;
}

// ---------------------------------------------------------------- pointing (docs/pointing.md)

function renderPointing(model) {
  if (!model) return;
  const syncs = model.syncs || [];
  const terms = (model.fitted || []).map((name) => `${name} ${model.terms_arcmin[name].toFixed(2)}′`);
  setText("pointing-summary", syncs.length
    ? `${syncs.length} sync(s) kept on the PC, RMS ${model.rms_arcmin.toFixed(2)}′; ${terms.join(", ")}`
    : "no syncs kept on the PC");
  const rows = syncs.map((sync) => {
    const row = document.createElement("tr");
    for (const text of [sync.number, sync.ra_j2000_hours.toFixed(4), sync.dec_j2000_deg.toFixed(3),
      `${sync.residual_arcmin.toFixed(2)}′`]) {
      const cell = document.createElement("td");
      cell.textContent = String(text);
      row.append(cell);
    }
    const remove = document.createElement("button");
    remove.type = "button";
    remove.textContent = "✕";
    remove.setAttribute("aria-label", `Remove sync ${sync.number}`);
    remove.disabled = document.body.dataset.readOnly === "true";
    remove.addEventListener("click", async () => renderPointing(await api("/api/pointing", { remove: sync.number })));
    const cell = document.createElement("td");
    cell.append(remove);
    row.append(cell);
    return row;
  });
  $("pointing-syncs").querySelector("tbody").replaceChildren(...rows);
  $("pointing-syncs").hidden = !syncs.length;
  $("pointing-clear").hidden = !syncs.length || document.body.dataset.readOnly === "true";
}

async function refreshPointing() {
  try { renderPointing(await (await fetch("/api/pointing")).json()); } catch (_) { /* shown next time */ }
}

function debounce(fn, ms) {
  let timer = null;
  return (...args) => { clearTimeout(timer); timer = setTimeout(() => fn(...args), ms); };
}

let searchSerial = 0;
let suggesting = false; // typing opens the list; Go and a chosen suggestion close it
async function searchNames(prefix) {
  if (!suggesting) return;
  const serial = ++searchSerial;
  const list = $("goto-suggestions");
  if (!prefix.trim()) { list.replaceChildren(); return; }
  let reply;
  try {
    const response = await fetch(`/api/search?q=${encodeURIComponent(prefix)}&limit=8`);
    reply = await response.json();
    if (!response.ok) { showMessage(reply.error || "search failed"); return; }
  } catch (error) {
    return;
  }
  if (serial !== searchSerial || !suggesting) return; // asked again since, or closed
  list.replaceChildren();
  for (const match of reply.matches) {
    const item = document.createElement("li");
    const button = document.createElement("button");
    button.type = "button";
    button.setAttribute("role", "option");
    const name = document.createElement("span");
    name.textContent = match.matched === match.name ? match.name : `${match.matched} (${match.name})`;
    const kind = document.createElement("span");
    kind.className = "kind";
    kind.textContent = match.mag != null ? `${match.type}, mag ${match.mag}` : match.type;
    button.append(name, kind);
    button.addEventListener("click", () => {
      $("goto-name").value = match.name;
      suggesting = false;
      list.replaceChildren();
      $("goto-name").focus();
    });
    item.append(button);
    list.append(item);
  }
}

async function gotoName(name) {
  const reply = await api("/api/goto", { name });
  if (reply) showMessage(`slewing to ${reply.object.name}`, "info");
}

async function gotoSelection() {
  const sel = view.selected;
  if (!sel) return;
  if (sel.name) { await gotoName(sel.name); return; }
  const reply = await api("/api/goto", { alt_deg: sel.alt, az_deg: sel.az % 360 });
  if (reply) showMessage(`slewing to alt ${fmtAngle(sel.alt)} az ${fmtAngle(sel.az)}`, "info");
}

// The pad, the keyboard and the gamepad: static/panel/motion.js and gamepad.js.
function setupPad() {
  Motion.setup();
  Gamepads.setup();
}

// This device's location (the browser's geolocation) into a site form's three fields.
function fillDeviceLocation(latId, lonId, elevId) {
  if (!navigator.geolocation) { showMessage("this browser cannot tell its location"); return; }
  navigator.geolocation.getCurrentPosition(
    (position) => {
      $(latId).value = position.coords.latitude.toFixed(5);
      $(lonId).value = position.coords.longitude.toFixed(5);
      if (position.coords.altitude != null) $(elevId).value = position.coords.altitude.toFixed(0);
    },
    (error) => showMessage(`no location: ${error.message}`),
  );
}

function setupNight() {
  const toggle = $("night-toggle");
  const apply = (on) => {
    document.body.classList.toggle("night", on);
    toggle.setAttribute("aria-pressed", String(on));
    Chart.redraw();
  };
  let stored = false;
  try { stored = localStorage.getItem("scopelink.night") === "1"; } catch (_) { /* private mode */ }
  apply(stored);
  toggle.addEventListener("click", () => {
    const on = !document.body.classList.contains("night");
    try { localStorage.setItem("scopelink.night", on ? "1" : "0"); } catch (_) { /* private mode */ }
    apply(on);
  });
}

function setup() {
  setupNight();
  Chart.init($("sky"), { onSelect: select });

  $("go-selected").addEventListener("click", gotoSelection);
  $("sync-selected").addEventListener("click", async () => {
    const sel = view.selected;
    if (sel && sel.name && (await api("/api/sync", { name: sel.name }))) {
      showMessage(`synced on ${sel.name}`, "info");
      refreshPointing();
    }
  });
  $("clear-selected").addEventListener("click", () => select(null));

  const nameInput = $("goto-name");
  const search = debounce(() => searchNames(nameInput.value), 120);
  nameInput.addEventListener("input", () => { suggesting = true; search(); });
  $("goto-form").addEventListener("submit", (event) => {
    event.preventDefault();
    suggesting = false; // an answer still on its way must not reopen the list
    $("goto-suggestions").replaceChildren();
    const name = nameInput.value.trim();
    if (name) gotoName(name);
  });

  $("abort").addEventListener("click", () => Motion.stop());
  $("tracking-apply").addEventListener("click", async () => {
    const mode = $("tracking-mode").value;
    const reply = await api("/api/tracking", { mode });
    if (reply) showMessage(`tracking set: ${reply.state.tracking}`, "info");
  });
  $("park").addEventListener("click", async () => {
    if (await api("/api/park")) showMessage("parking: the mount is on its way to the park position", "info");
  });
  $("unpark").addEventListener("click", async () => {
    const reply = await api("/api/unpark");
    if (reply) showMessage(reply.resume ? `unparked: ${reply.resume}` : "unparked", "info");
  });

  $("site-form").addEventListener("submit", async (event) => {
    event.preventDefault();
    const body = {
      latitude_deg: Number($("site-lat").value),
      longitude_deg: Number($("site-lon").value),
    };
    if ($("site-elev").value !== "") body.elevation_m = Number($("site-elev").value);
    const reply = await api("/api/site", body);
    if (reply) {
      view.mount = reply.mount; renderMount();
      const site = reply.mount.site;
      showMessage(`site set: ${site.latitude_deg.toFixed(4)}°, ${site.longitude_deg.toFixed(4)}°, ${site.elevation_m.toFixed(0)} m`, "info");
    }
  });
  $("site-here").addEventListener("click", () => fillDeviceLocation("site-lat", "site-lon", "site-elev"));
  $("time-push").addEventListener("click", async () => {
    const sent = new Date().toISOString();
    if (await api("/api/time", { utc: sent })) showMessage(`mount clock set to ${sent.slice(0, 19).replace("T", " ")} UTC`, "info");
  });
  $("traffic-pause").addEventListener("change", (event) => { traffic.paused = event.target.checked; });

  $("pointing-clear").addEventListener("click", async () => renderPointing(await api("/api/pointing", { clear: true })));
  refreshPointing();
  setInterval(refreshPointing, 10000);  // syncs from other front ends show within 10 s

  setupPad();
  applyAccess();
  connect();
}

document.addEventListener("DOMContentLoaded", setup);
