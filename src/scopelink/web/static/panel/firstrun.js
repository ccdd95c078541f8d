"use strict";
// First run (docs/dashboard.md, "First run"): when no site is saved, ask once for the site
// (the mount's, this device's location, or typed) and check the clock, then save the site to
// the settings file through POST /api/setup. Uses app.js's $, api, view, renderMount,
// fillDeviceLocation and showMessage.

const FirstRun = (() => {
  const CLOCK_WARN_S = 60; // a mount clock further off than this is worth setting

  function fill(site) {
    $("fr-lat").value = String(site.latitude_deg);
    $("fr-lon").value = String(site.longitude_deg);
    $("fr-elev").value = String(site.elevation_m);
  }

  function span(seconds) {
    const s = Math.abs(seconds);
    if (s >= 86400) return `${Math.floor(s / 86400)} d ${Math.floor((s % 86400) / 3600)} h`;
    if (s >= 3600) return `${Math.floor(s / 3600)} h ${Math.floor((s % 3600) / 60)} min`;
    if (s >= 60) return `${Math.floor(s / 60)} min ${Math.round(s % 60)} s`;
    return `${Math.round(s)} s`;
  }

  function showClock(mountUtc) {
    const device = new Date();
    const skew = (new Date(mountUtc) - device) / 1000;
    const differs = Math.abs(skew) < 2 ? "the same" : `${span(skew)} ${skew > 0 ? "ahead" : "behind"}`;
    $("fr-clock").textContent = `This device: ${device.toISOString().replace("T", " ").slice(0, 19)} UTC; ` +
      `the mount: ${mountUtc.replace("T", " ").slice(0, 19)} UTC (${differs}).`;
    $("fr-time").checked = Math.abs(skew) > CLOCK_WARN_S;
  }

  async function open() {
    let status, access;
    try {
      status = await (await fetch("/api/setup")).json();
      access = await (await fetch("/api/access")).json();
    } catch (_) { return; }
    if (!status || !status.needed || !access || access.read_only) return; // read-only: cannot save
    $("fr-where").textContent = status.where;
    fill(status.site);
    showClock(status.mount_utc);
    $("firstrun").hidden = false;
    $("fr-lat").focus();
    $("fr-device").onclick = () => fill(status.site);
  }

  async function save(event) {
    event.preventDefault();
    const body = { latitude_deg: Number($("fr-lat").value), longitude_deg: Number($("fr-lon").value) };
    if ($("fr-elev").value !== "") body.elevation_m = Number($("fr-elev").value);
    if ($("fr-time").checked) body.utc = new Date().toISOString();
    const reply = await api("/api/setup", body);
    if (!reply) return; // the error is shown; the form stays for another try
    $("firstrun").hidden = true;
    view.mount = reply.mount;
    renderMount();
    showMessage(`site saved to ${reply.saved_to}${reply.time_set ? "; mount clock set" : ""}`, "info");
  }

  function setup() {
    $("firstrun-form").addEventListener("submit", save);
    $("fr-here").addEventListener("click", () => fillDeviceLocation("fr-lat", "fr-lon", "fr-elev"));
    $("fr-later").addEventListener("click", () => { $("firstrun").hidden = true; });
    open();
  }

  return { setup };
})();

document.addEventListener("DOMContentLoaded", FirstRun.setup);
