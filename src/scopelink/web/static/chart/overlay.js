// What the chart draws over the sky: the forbidden sky (below the mount's horizon profile,
// above its maximum altitude, the Sun's avoidance zone), the planned slew path, the track from
// GET /api/track, the target, the selection, where the mount points and the eyepiece or camera
// frame around it.
"use strict";

import { axisPath, skyPoint } from "./sphere.js";

// limits: the hello's mount.limits ({horizon: [[az, alt], ...], max_altitude_deg, ...}).
export function drawLimits(scene, limits) {
  if (!limits) return;
  const { ctx, path, c } = scene;
  ctx.fillStyle = c.limit; ctx.strokeStyle = c.limitEdge; ctx.lineWidth = 1.2;
  const ring = limits.horizon.map(([az, alt]) => skyPoint(alt, az));
  ring.push(ring[0]);
  // The forbidden side is the one holding the nadir, whatever the profile's shape.
  let below = { type: "Polygon", coordinates: [ring] };
  if (!d3.geoContains(below, [0, -90])) below = { type: "Polygon", coordinates: [ring.slice().reverse()] };
  ctx.beginPath(); path(below); ctx.fill(); ctx.stroke();
  if (limits.max_altitude_deg < 90) {
    ctx.beginPath(); path(d3.geoCircle().center([0, 90]).radius(90 - limits.max_altitude_deg).precision(1)());
    ctx.fill(); ctx.stroke();
  }
}

// The Sun's avoidance zone: the circle of `radius_deg` around the Sun (state.sun).
export function drawSunZone(scene, sun) {
  if (!sun || !(sun.radius_deg > 0)) return false;
  const { ctx, path, c } = scene;
  ctx.fillStyle = c.limit; ctx.strokeStyle = c.limitEdge; ctx.lineWidth = 1.2;
  ctx.beginPath(); path(d3.geoCircle().center(skyPoint(sun.alt, sun.az)).radius(sun.radius_deg).precision(1)());
  ctx.fill(); ctx.stroke();
  return true;
}

// The planned slew (the mount's axis path from where it points to the target) while slewing;
// the track of GET /api/track (J2000) when the server has one.
export function drawPaths(scene, state, mount, track, frame) {
  const { ctx, path, c } = scene;
  const drawn = { path: false, track: false };
  const target = state && state.target_altaz;
  if (state && state.slewing && target && state.alt_deg != null && mount) {
    const from = { alt: state.alt_deg, az: state.az_deg };
    const points = axisPath(from, target, mount.capabilities.alignment_mode, mount.site.latitude_deg);
    ctx.strokeStyle = c.path; ctx.lineWidth = 1.5; ctx.setLineDash([5, 4]);
    ctx.beginPath(); path({ type: "LineString", coordinates: points }); ctx.stroke();
    ctx.setLineDash([]);
    drawn.path = true;
  }
  if (track && frame && track.path.length > 1) {
    const points = track.path.map(([ra, dec]) => frame.toSky(ra, dec));
    ctx.strokeStyle = c.track; ctx.lineWidth = 1.5;
    ctx.beginPath(); path({ type: "LineString", coordinates: points }); ctx.stroke();
    drawn.track = true;
  }
  return drawn;
}

function crosshair(ctx, x, y) {
  ctx.beginPath(); ctx.arc(x, y, 9, 0, 2 * Math.PI); ctx.stroke();
  ctx.beginPath();
  ctx.moveTo(x - 15, y); ctx.lineTo(x - 5, y); ctx.moveTo(x + 5, y); ctx.lineTo(x + 15, y);
  ctx.moveTo(x, y - 15); ctx.lineTo(x, y - 5); ctx.moveTo(x, y + 5); ctx.lineTo(x, y + 15);
  ctx.stroke();
}

// The eyepiece (circle, `field.height` null) or camera (rectangle) field around the mount, in
// degrees, drawn once it spans at least 1/10 of the canvas; the rectangle is upright on the
// chart (the camera's rotation is not known).
function drawField(scene, centre, field) {
  const { ctx, path, c } = scene;
  const size = Math.max(field.width, field.height || 0);
  if (size * scene.pxPerDeg < scene.width / 10) return false;
  ctx.strokeStyle = c.frame; ctx.lineWidth = 1.5;
  if (!field.height) {
    ctx.beginPath(); path(d3.geoCircle().center(centre).radius(field.width / 2).precision(0.2)()); ctx.stroke();
  } else {
    const xy = scene.project(centre);
    const w = field.width * scene.pxPerDeg, h = field.height * scene.pxPerDeg;
    ctx.strokeRect(xy[0] - w / 2, xy[1] - h / 2, w, h);
  }
  return true;
}

// Returns what it drew and the boxes labels must keep clear of.
export function drawMarkers(scene, state, selected, field, track) {
  const { ctx, c } = scene;
  const keepOut = [];
  const result = { mount: null, target: null, frame: false, error: null };
  if (selected) {
    const xy = scene.screen(skyPoint(selected.alt, selected.az));
    if (xy) {
      ctx.strokeStyle = c.selected; ctx.lineWidth = 2;
      ctx.beginPath(); ctx.arc(xy[0], xy[1], 10, 0, 2 * Math.PI); ctx.stroke();
    }
  }
  const target = state && state.target_altaz;
  if (target) {
    const xy = scene.screen(skyPoint(target.alt, target.az));
    if (xy) {
      ctx.strokeStyle = c.target; ctx.lineWidth = 2;
      ctx.strokeRect(xy[0] - 7, xy[1] - 7, 14, 14);
      keepOut.push([xy[0] - 8, xy[1] - 8, xy[0] + 8, xy[1] + 8]);
      result.target = xy;
      if (track && track.error_arcsec != null) {
        const text = `${track.error_arcsec.toFixed(0)}″`;
        ctx.fillStyle = c.target; ctx.font = "11px system-ui, sans-serif"; ctx.textBaseline = "top";
        ctx.fillText(text, xy[0] + 10, xy[1] + 8);
        keepOut.push([xy[0] + 8, xy[1] + 6, xy[0] + 12 + ctx.measureText(text).width, xy[1] + 22]);
        result.error = text;
      }
    }
  }
  if (state && state.alt_deg != null) {
    const centre = skyPoint(state.alt_deg, state.az_deg);
    const xy = scene.screen(centre);
    if (xy) {
      result.frame = drawField(scene, centre, field);
      ctx.strokeStyle = c.mount; ctx.lineWidth = 2;
      crosshair(ctx, xy[0], xy[1]);
      keepOut.push([xy[0] - 10, xy[1] - 10, xy[0] + 10, xy[1] + 10]); // the ring; ticks may be crossed
      result.mount = xy;
    }
  }
  return { result, keepOut };
}
