"use strict";
// The "Sky Commander memory" and push-to panel (docs/dashboard.md). Uses app.js's $, api,
// showMessage, fmtHours and fmtDeg. Push-to figures come from /api/pushto twice a second.

const PUSHTO_INTERVAL_MS = 500;
const pushto = { target: null, timer: null };

async function refreshPushTo() {
  if (!pushto.target) return;
  let reply = null;
  try {
    const response = await fetch(`/api/pushto?name=${encodeURIComponent(pushto.target)}`);
    reply = await response.json();
    if (!response.ok) { $("pushto-figures").textContent = reply.error || response.statusText; return; }
  } catch (error) {
    $("pushto-figures").textContent = `cannot reach scopelink: ${error.message}`;
    return;
  }
  $("pushto-figures").textContent = reply.text;
}

function startPushTo(name) {
  clearInterval(pushto.timer);
  pushto.target = name;
  refreshPushTo();
  pushto.timer = setInterval(refreshPushTo, PUSHTO_INTERVAL_MS);
}

function stopPushTo() {
  clearInterval(pushto.timer);
  pushto.target = null;
  $("pushto-figures").textContent = "—";
}

function renderSlots(slots) {
  const rows = slots.map((entry) => {
    const row = document.createElement("tr");
    const cells = [
      String(entry.slot).padStart(2, "0"),
      entry.label,
      `${fmtHours(entry.ra_j2000_hours)} ${fmtDeg(entry.dec_j2000_deg)}`,
    ];
    for (const text of cells) {
      const cell = document.createElement("td");
      cell.textContent = text;
      row.append(cell);
    }
    const action = document.createElement("td");
    const button = document.createElement("button");
    button.type = "button";
    button.textContent = "clear";
    button.addEventListener("click", () => clearSlots({ slot: entry.slot }));
    action.append(button);
    row.append(action);
    return row;
  });
  $("slots").tBodies[0].replaceChildren(...rows);
}

async function loadSlots() {
  try {
    const reply = await (await fetch("/api/skycommander/slots")).json();
    $("skycommander-memory").hidden = !reply.available;
    if (reply.available) renderSlots(reply.slots);
  } catch (_) { /* the live link reports an unreachable server */ }
}

async function clearSlots(body) {
  const reply = await api("/api/skycommander/clear", body);
  if (reply) { renderSlots(reply.slots); showMessage(`cleared ${reply.cleared.length} slot(s)`, "info"); }
}

function setupSkyCommander() {
  $("pushto-form").addEventListener("submit", (event) => {
    event.preventDefault();
    const name = $("pushto-name").value.trim();
    if (name) startPushTo(name);
  });
  $("pushto-stop").addEventListener("click", stopPushTo);
  $("slot-form").addEventListener("submit", async (event) => {
    event.preventDefault();
    const name = $("slot-name").value.trim();
    if (!name) return;
    const body = { name };
    if ($("slot-number").value !== "") body.slot = Number($("slot-number").value);
    const reply = await api("/api/skycommander/upload", body);
    if (reply) {
      renderSlots(reply.slots);
      const entry = reply.written[0];
      showMessage(`stored ${entry.label} in slot ${String(entry.slot).padStart(2, "0")}`, "info");
    }
  });
  $("slots-clear").addEventListener("click", () => clearSlots({}));
  loadSlots();
}

document.addEventListener("DOMContentLoaded", setupSkyCommander);
