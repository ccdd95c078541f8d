// What the chart draws that does not come over the WebSocket: the sky data shipped with the
// page (static/sky/, reduced from d3-celestial) and the deep-sky list the server builds once
// from the catalogue (GET /api/sky/deepsky). Each is fetched once per page load; a missing
// piece leaves its layer empty, never the chart blank.
"use strict";

async function getJson(url) {
  try {
    const response = await fetch(url);
    if (!response.ok) return null;
    return await response.json();
  } catch (_) {
    return null;
  }
}

import { unit } from "./sphere.js";

// J2000 unit vectors of a flat [ra, dec, ...] list taken every `stride` numbers.
function vectors(flat, stride) {
  const n = flat.length / stride;
  const out = new Float64Array(3 * n);
  for (let i = 0; i < n; i++) out.set(unit(flat[stride * i], flat[stride * i + 1]), 3 * i);
  return out;
}

export const sky = {
  stars: [], // [ra, dec, mag, ra, dec, mag, ...] brightest first
  starVectors: new Float64Array(0), // their J2000 unit vectors, for culling
  lines: [], // [[abbr, [[[ra, dec], ...], ...]], ...]
  names: [], // [[abbr, name, ra, dec, rank], ...]
  milkyway: [], // MultiPolygon coordinates per level, faint to bright
  deepsky: [], // [{name, type, ra, dec, mag, major, minor, pa, v}, ...] brightest first
};

// Calls `changed` after each piece arrives.
export function loadSky(changed) {
  getJson("/static/sky/stars.json").then((stars) => {
    if (!stars) return;
    sky.stars = stars; sky.starVectors = vectors(stars, 3); changed();
  });
  getJson("/static/sky/constellations.json").then((c) => {
    if (c) { sky.lines = c.lines; sky.names = c.names; changed(); }
  });
  getJson("/static/sky/milkyway.json").then((m) => { if (m) { sky.milkyway = m.levels; changed(); } });
  getJson("/api/sky/deepsky").then((d) => {
    if (!d) return;
    const at = Object.fromEntries(d.fields.map((field, i) => [field, i]));
    sky.deepsky = d.objects.map((row) => ({
      name: row[at.name], type: row[at.type], ra: row[at.ra_deg], dec: row[at.dec_deg],
      mag: row[at.mag], major: row[at.major_arcmin], minor: row[at.minor_arcmin], pa: row[at.pa_deg],
      v: unit(row[at.ra_deg], row[at.dec_deg]),
    }));
    changed();
  });
}

// GET /api/track (the mount's planned or followed track, when the server has it): a 404, an
// error or anything malformed gives null and the chart draws no track.
export async function loadTrack() {
  const track = await getJson("/api/track");
  if (!track || !Array.isArray(track.path)) return null;
  const path = track.path.filter((p) => Array.isArray(p) && Number.isFinite(p[0]) && Number.isFinite(p[1]));
  const error = Number.isFinite(track.error_arcsec) ? track.error_arcsec : null;
  return { target: track.target, kind: track.kind, error_arcsec: error, path };
}
