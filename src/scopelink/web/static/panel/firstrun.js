"use strict";
// First run (docs/dashboard.md, "First run"): when no site is saved, ask once for the site
// (the mount's, this device's location, or typed) and check the clock, then save the site to
// the settings file through POST /api/setup. Uses app.js's $, api, view, renderMount and
// showMessage.

const FirstRun = (() => {
  const CLOCK_WARN_S = 60; // a mount clock further off than this is worth setting

  function fill(site) {
    $("fr-lat").value = String(site.latitude_deg);
    $("fr-lon").value = String(site.longitude_deg);
    $("fr-elev").value = String(site.elevation_m);
  }

  function showClock(mountUtc) {
    const device = new Date();
    const skew = (new Date(mountUtc) - device) / 1000;
    const text = `This device: ${device.toISOString().slice(11, 19)} UTC; the mount: ` +
      `${mountUtc.slice(11, 19)} UTC (${Math.abs(skew) < 2 ? "the same" : `${skew > 0 ? "+" : "−"}${Math.abs(skew).toFixed(0)} s`}).`;
    $("fr-clock").textContent = text;
    $("fr-time").checked = Math.abs(skew) > CLOCK_WARN_S;
  }

  async function open() {
    let status;
    try { status = await (await fetch("/api/setup")).json(); } catch (_) { return; }
    if (!status || !status.needed || document.body.dataset.readOnly === "true") return;
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

  function here() {
    if (!navigator.geolocation) { showMessage("this browser cannot tell its location"); return; }
    navigator.geolocation.getCurrentPosition(
      (position) => {
        $("fr-lat").value = position.coords.latitude.toFixed(5);
        $("fr-lon").value = position.coords.longitude.toFixed(5);
        if (position.coords.altitude != null) $("fr-elev").value = position.coords.altitude.toFixed(0);
      },
      (error) => showMessage(`no location: ${error.message}`),
    );
  }

  function setup() {
    $("firstrun-form").addEventListener("submit", save);
    $("fr-here").addEventListener("click", here);
    $("fr-later").addEventListener("click", () => { $("firstrun").hidden = true; });
    open();
  }

  return { setup };
})();

document.addEventListener("DOMContentLoaded", FirstRun.setup);
