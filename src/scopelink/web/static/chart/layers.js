// The sky layers of the chart, back to front: the sky's colour (twilight from the Sun's
// altitude), the Milky Way, the altitude/azimuth grid with the horizon and the meridian,
// constellation lines, the star field, deep-sky objects and the server's named objects (bright
// stars, Sun, Moon, planets). Each drawing function takes the scene (see chart.js) and returns
// what it drew that can be clicked or labelled.
"use strict";

import { RAD, skyPoint } from "./sphere.js";

export const palettes = {
  day: {
    ground: "rgba(20,26,36,0.82)", grid: "rgba(120,150,200,0.22)", horizon: "#6b7b96",
    meridian: "rgba(150,170,220,0.45)", limit: "rgba(217,83,79,0.22)", limitEdge: "#d9534f",
    star: "#e8eefc", below: "#3a4458", label: "#9fb0cc", milkyway: "rgba(170,190,255,0.055)",
    constellation: "rgba(110,150,220,0.55)", constellationName: "rgba(130,160,220,0.75)",
    planet: "#ffd27f", moon: "#f4f4f4", sun: "#ffb000", mount: "#5fa8ff", target: "#4caf50",
    selected: "#ff7ad9", path: "#4caf50", track: "#7fd3ff", frame: "#ffe066",
    galaxy: "#e0707a", open: "#e6d36a", globular: "#e6b35a", planetary: "#5fd0d0",
    nebula: "#6ad08a", "cluster-nebula": "#6ad08a", text: "#9fb0cc",
    twilight: [[0, [58, 110, 165]], [-6, [30, 56, 100]], [-12, [14, 28, 56]], [-18, [6, 16, 31]]],
  },
  night: {
    ground: "rgba(8,0,0,0.85)", grid: "rgba(90,0,0,0.45)", horizon: "#5a0a0a",
    meridian: "rgba(120,10,10,0.6)", limit: "rgba(120,0,0,0.35)", limitEdge: "#7a1010",
    star: "#d02020", below: "#3a0505", label: "#8a1515", milkyway: "rgba(120,0,0,0.07)",
    constellation: "rgba(110,0,0,0.8)", constellationName: "rgba(130,10,10,0.9)",
    planet: "#e03030", moon: "#e03030", sun: "#e03030", mount: "#ff3030", target: "#b01a1a",
    selected: "#ff5050", path: "#b01a1a", track: "#c02020", frame: "#ff4040",
    galaxy: "#a01818", open: "#a01818", globular: "#a01818", planetary: "#a01818",
    nebula: "#a01818", "cluster-nebula": "#a01818", text: "#8a1515",
    twilight: [[0, [34, 0, 0]], [-6, [18, 0, 0]], [-12, [8, 0, 0]], [-18, [0, 0, 0]]],
  },
};

// The sky's colour for the Sun's altitude: day, civil, nautical, astronomical twilight, night.
export function skyColour(sunAlt, colours) {
  const stops = colours.twilight;
  if (sunAlt == null || sunAlt <= stops[stops.length - 1][0]) return `rgb(${stops[stops.length - 1][1]})`;
  if (sunAlt >= stops[0][0]) return `rgb(${stops[0][1]})`;
  for (let i = 1; i < stops.length; i++) {
    const [a, ca] = stops[i - 1], [b, cb] = stops[i];
    if (sunAlt >= b) {
      const f = (sunAlt - b) / (a - b);
      return `rgb(${cb.map((c, j) => Math.round(c + f * (ca[j] - c))).join(",")})`;
    }
  }
  return `rgb(${stops[0][1]})`;
}

// The faintest magnitude the sky's brightness lets through: none by day, 8 by night, linear in
// the Sun's depth in between (about 3.8 at the end of civil twilight, 5.9 of nautical).
// `twilight`: the server's boundaries ({phase: the Sun's altitude it holds above}, the hello's
// twilight_deg from web/almanac.py); unknown, like the Sun, the sky hides nothing.
export function skyLimit(sunAlt, twilight) {
  if (sunAlt == null || !twilight) return 99;
  const sunset = twilight.day, dark = twilight["astronomical twilight"];
  if (sunAlt > sunset) return -99;
  return 2 + ((Math.max(dark, sunAlt) - sunset) / (dark - sunset)) * 6;
}
// Deep-sky objects and the Milky Way only once the Sun is down by the end of civil twilight (6°).
function tooBright(scene) {
  return scene.sunAlt != null && !!scene.twilight && scene.sunAlt > scene.twilight["civil twilight"];
}

export function drawBackground(scene) {
  const { ctx, path, c } = scene;
  ctx.fillStyle = skyColour(scene.sunAlt, c);
  ctx.beginPath(); path({ type: "Sphere" }); ctx.fill();
}

export function drawMilkyWay(scene, levels) {
  const { ctx, roughPath, c } = scene;
  if (tooBright(scene)) return 0;
  ctx.fillStyle = c.milkyway;
  for (const coordinates of levels) {
    ctx.beginPath(); roughPath({ type: "MultiPolygon", coordinates }); ctx.fill();
  }
  return levels.length;
}

// The ground below the horizon, shaded over whatever sky layers lie there.
export function drawGround(scene) {
  const { ctx, path, c } = scene;
  const ring = [];
  for (let az = 0; az <= 360; az += 5) ring.push(skyPoint(0, -az));
  ctx.fillStyle = c.ground;
  ctx.beginPath(); path({ type: "Polygon", coordinates: [ring] }); ctx.fill();
}

export function drawGrid(scene) {
  const { ctx, path, c } = scene;
  const lines = [];
  for (const alt of [30, 60]) lines.push(d3.geoCircle().center([0, 90]).radius(90 - alt).precision(2)().coordinates[0]);
  for (let az = 0; az < 360; az += 45) lines.push([skyPoint(0, az), skyPoint(89.9, az)]);
  ctx.strokeStyle = c.grid; ctx.lineWidth = 1;
  ctx.beginPath(); path({ type: "MultiLineString", coordinates: lines }); ctx.stroke();
  // The meridian: north point, zenith, south point.
  ctx.strokeStyle = c.meridian; ctx.setLineDash([6, 5]);
  ctx.beginPath(); path({ type: "LineString", coordinates: [skyPoint(0, 0), skyPoint(90, 0), skyPoint(0, 180)] }); ctx.stroke();
  ctx.setLineDash([]);
  ctx.strokeStyle = c.horizon; ctx.lineWidth = 1.5;
  ctx.beginPath(); path(d3.geoCircle().center([0, 90]).radius(90).precision(2)()); ctx.stroke();
  const labels = [];
  for (const [letter, az] of [["N", 0], ["E", 90], ["S", 180], ["W", 270]]) {
    const p = scene.screen(skyPoint(-2.5, az));
    if (p) labels.push({ text: letter, x: p[0], y: p[1], r: 0, priority: -100, font: "bold 13px system-ui, sans-serif", size: 13, colour: c.text });
  }
  return labels;
}

export function drawConstellations(scene, lines, names) {
  const { ctx, path, c } = scene;
  ctx.strokeStyle = c.constellation; ctx.lineWidth = 1;
  ctx.globalAlpha = skyLimit(scene.sunAlt, scene.twilight) < 0 ? 0.4 : 1; // faint by day
  ctx.beginPath();
  for (const [, coordinates] of lines) path({ type: "MultiLineString", coordinates });
  ctx.stroke();
  ctx.globalAlpha = 1;
  const labels = [];
  const maxRank = scene.fov > 150 ? 1 : scene.fov > 90 ? 2 : 3;
  for (const [, name, p, rank] of names) {
    if (rank > maxRank) continue;
    const xy = scene.screen(p);
    if (xy) labels.push({ text: name.toUpperCase(), x: xy[0], y: xy[1], r: 0, priority: 2 + rank, font: "10px system-ui, sans-serif", size: 10, colour: c.constellationName });
  }
  return { count: lines.length, labels };
}

// Fainter stars only as the field narrows: magnitude 4.5 for the whole sky, 7.5 from 20° down.
export function starLimit(fov) {
  return Math.min(7.5, 4.5 + 3 * Math.log2(200 / fov) / Math.log2(200 / 20));
}

function starRadius(mag, fov) {
  if (mag == null) return 3;
  const zoom = 1 + 0.25 * Math.log2(200 / fov);
  return Math.max(0.7, Math.min(6, Math.max(0.5, 3.6 - 0.55 * mag) * zoom));
}

// A J2000 object near the view (`near`: the view's centre as a J2000 vector, the cosine of
// the culling radius, the J2000 -> sky conversion): its [lon, lat], or null.
function nearby(near, vectors, i, ra, dec) {
  const c = near.centre;
  if (vectors[3 * i] * c[0] + vectors[3 * i + 1] * c[1] + vectors[3 * i + 2] * c[2] < near.cos) return null;
  return near.toSky(ra, dec);
}

// stars: a flat [ra, dec, mag, ...] list, brightest first; vectors: their J2000 unit vectors.
export function drawStars(scene, stars, vectors, near) {
  const { ctx, c } = scene;
  const limit = Math.min(starLimit(scene.fov), skyLimit(scene.sunAlt, scene.twilight));
  ctx.fillStyle = c.star;
  let count = 0;
  for (let i = 0; 3 * i < stars.length; i++) {
    const mag = stars[3 * i + 2];
    if (mag > limit) break; // brightest first
    const p = nearby(near, vectors, i, stars[3 * i], stars[3 * i + 1]);
    const xy = p && scene.screen(p);
    if (!xy) continue;
    ctx.globalAlpha = p[1] < 0 ? 0.35 : 1;
    ctx.beginPath(); ctx.arc(xy[0], xy[1], starRadius(mag, scene.fov), 0, 2 * Math.PI); ctx.fill();
    count++;
  }
  ctx.globalAlpha = 1;
  return count;
}

// Deep-sky objects drawn: magnitude 6 for the whole sky (Messier and Caldwell from 120°), all
// of the server's list (to magnitude 13) from a 20° field.
export function deepSkyLimit(fov) {
  return Math.min(99, 6 + 7 * Math.log2(200 / fov) / Math.log2(200 / 20));
}

function deepSkySymbol(ctx, type, x, y, rx, ry, angle) {
  ctx.beginPath();
  switch (type) {
    case "galaxy":
      ctx.ellipse(x, y, rx, Math.max(ry, 1.5), angle, 0, 2 * Math.PI);
      break;
    case "globular":
      ctx.arc(x, y, rx, 0, 2 * Math.PI);
      ctx.moveTo(x - rx, y); ctx.lineTo(x + rx, y); ctx.moveTo(x, y - rx); ctx.lineTo(x, y + rx);
      break;
    case "planetary":
      ctx.arc(x, y, rx * 0.6, 0, 2 * Math.PI);
      for (const [dx, dy] of [[1, 0], [-1, 0], [0, 1], [0, -1]]) {
        ctx.moveTo(x + dx * rx * 0.6, y + dy * rx * 0.6); ctx.lineTo(x + dx * rx * 1.2, y + dy * rx * 1.2);
      }
      break;
    case "open":
      ctx.setLineDash([2, 2]); ctx.arc(x, y, rx, 0, 2 * Math.PI);
      break;
    case "cluster-nebula":
      ctx.rect(x - rx, y - rx, 2 * rx, 2 * rx); ctx.moveTo(x + rx * 0.7, y); ctx.arc(x, y, rx * 0.7, 0, 2 * Math.PI);
      break;
    default: // nebulae
      ctx.rect(x - rx, y - ry, 2 * rx, 2 * ry);
  }
  ctx.stroke();
  ctx.setLineDash([]);
}

// objects: [{name, type, ra, dec, mag, major, minor, pa, v}] (data.js), brightest first.
export function drawDeepSky(scene, objects, near) {
  const { ctx, c } = scene;
  const limit = deepSkyLimit(scene.fov);
  if (tooBright(scene)) return { count: 0, clickable: [], labels: [] };
  const pxPerDeg = scene.pxPerDeg;
  const clickable = [], labels = [];
  ctx.lineWidth = 1.1;
  for (const obj of objects) {
    const named = obj.name.startsWith("M ") || obj.name.startsWith("C ");
    const mag = obj.mag == null ? 14 : obj.mag;
    if (mag > limit && !(named && scene.fov <= 120)) continue;
    const c0 = near.centre;
    if (obj.v[0] * c0[0] + obj.v[1] * c0[1] + obj.v[2] * c0[2] < near.cos) continue;
    const p = near.toSky(obj.ra, obj.dec);
    const xy = scene.screen(p);
    if (!xy) continue;
    const major = obj.major || 1;
    const rx = Math.max(3.5, (major / 120) * pxPerDeg);
    const ry = obj.minor ? Math.max(2, (obj.minor / 120) * pxPerDeg) : rx;
    const angle = obj.pa != null && rx > 6 ? scene.northAngle(obj, p) - obj.pa * RAD : 0;
    ctx.strokeStyle = c[obj.type] || c.nebula;
    ctx.globalAlpha = p[1] < 0 ? 0.35 : 1;
    deepSkySymbol(ctx, obj.type, xy[0], xy[1], rx, obj.type === "galaxy" ? ry : rx, angle);
    clickable.push({ name: obj.name, x: xy[0], y: xy[1] });
    if (p[1] >= 0) labels.push({ text: obj.name, x: xy[0], y: xy[1], r: Math.min(rx, 12), priority: 10 + mag, font: "10px system-ui, sans-serif", size: 10, colour: c[obj.type] || c.nebula });
  }
  ctx.globalAlpha = 1;
  return { count: clickable.length, clickable, labels };
}

function objectStyle(obj, c) {
  switch (obj.kind) {
    case "sun": return { colour: c.sun, radius: 7, priority: -10 };
    case "moon": return { colour: c.moon, radius: 6, priority: -9 };
    case "planet": return { colour: c.planet, radius: 3.5, priority: -8 };
    case "dwarf planet": return { colour: c.planet, radius: 2.5, priority: 8 };
    default: return { colour: c.star, radius: null, priority: obj.mag == null ? 5 : obj.mag };
  }
}

// The server's objects (observed alt/az): named bright stars, the Sun, Moon and planets.
export function drawNamedObjects(scene, objects) {
  const { ctx, c } = scene;
  const clickable = [], labels = [];
  const labelMag = 1.5 + 4 * Math.log2(200 / scene.fov) / Math.log2(200 / 20);
  for (const obj of objects) {
    const p = skyPoint(obj.alt, obj.az);
    const xy = scene.screen(p);
    if (!xy) continue;
    const style = objectStyle(obj, c);
    const r = style.radius || starRadius(obj.mag, scene.fov);
    ctx.fillStyle = obj.alt < 0 ? c.below : style.colour;
    ctx.beginPath(); ctx.arc(xy[0], xy[1], r, 0, 2 * Math.PI); ctx.fill();
    clickable.push({ name: obj.name, x: xy[0], y: xy[1] });
    if (obj.alt >= 0 && (style.radius || (obj.mag != null && obj.mag < labelMag))) {
      labels.push({ text: obj.name, x: xy[0], y: xy[1], r, priority: style.priority, font: "11px system-ui, sans-serif", size: 11, colour: c.label });
    }
  }
  return { count: clickable.length, clickable, labels };
}
