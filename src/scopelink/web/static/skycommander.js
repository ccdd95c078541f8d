"use strict";
// The "Sky Commander memory" and push-to panel (docs/dashboard.md). Uses app.js's $, api,
// showMessage, fmtHours and fmtDeg. The push-to target is set with POST /api/pushto; its figures
// ride on every WebSocket update (state.pushto), for every page: one telescope, one target.

function renderPushTo(figures) {
  const box = $("pushto-view");
  if (!figures) {
    box.hidden = true;
    if ($("pushto-figures").textContent !== "—") $("pushto-figures").textContent = "—";
    return;
  }
  if (figures.error) {
    box.hidden = true;
    $("pushto-figures").textContent = `${figures.target}: ${figures.error}`;
    return;
  }
  $("pushto-figures").textContent = figures.text;
  box.hidden = false;
  box.dataset.onTarget = String(figures.on_target);
  const up = figures.up_deg, right = figures.right_deg;
  $("pushto-vertical-arrow").textContent = up >= 0 ? "▲" : "▼";
  $("pushto-vertical").textContent = `${up >= 0 ? "up" : "down"} ${Math.abs(up).toFixed(1)}°`;
  $("pushto-horizontal-arrow").textContent = right >= 0 ? "▶" : "◀";
  $("pushto-horizontal").textContent = `${right >= 0 ? "right" : "left"} ${Math.abs(right).toFixed(1)}°`;
}

async function startPushTo(name) {
  const reply = await api("/api/pushto", { name });
  if (reply) showMessage(`push-to: ${reply.target}`, "info");
}

async function stopPushTo() {
  if (await api("/api/pushto", {})) renderPushTo(null);
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
  document.addEventListener("scopelink:state", (event) => renderPushTo(event.detail.pushto));
  loadSlots();
}

document.addEventListener("DOMContentLoaded", setupSkyCommander);
