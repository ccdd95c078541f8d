// scopelink sky chart (docs/dashboard.md, "Sky chart"): a stereographic view of the sky
// (d3-geo) that zooms from the whole sky to a 1° field. app.js talks to it only through the
// small interface at the end (window.Chart). The chart draws only when something it shows has
// changed (new data it would draw differently, an interaction, the night mode), at most once per
// animation frame, never in a loop.
import "./vendor/d3-array.min.js";
import "./vendor/d3-geo.min.js";
import { RAD, altAz, lonLatVector, makeFrame, skyPoint } from "./chart/sphere.js";
import { loadSky, loadTrack, sky } from "./chart/data.js";
import { placeLabels } from "./chart/labels.js";
import {
  drawBackground, drawConstellations, drawDeepSky, drawGrid, drawGround, drawMilkyWay,
  drawNamedObjects, drawStars, palettes, skyLimit,
} from "./chart/layers.js";
import { drawLimits, drawMarkers, drawPaths, drawSunZone } from "./chart/overlay.js";
import { attachControls, buildToolbar, followMount, loadField, view } from "./chart/view.js";

const CLICK_RADIUS_PX = 18; // a finger-sized target
const LABEL_AREA_PX2 = 7000; // at most one label per this much canvas
const SCREEN_MARGIN_PX = 20;
const FOLLOW_STEP_PX = 2; // a followed mount is re-centred once it is this far off the centre

const data = { mount: null, state: null, sky: [], selected: null, frame: null, track: null, twilight: null };
const hooks = { onSelect: () => {} };
const chart = { canvas: null, ctx: null, width: 0, height: 0, field: loadField(), twilight: "" };
let cache = null; // the J2000 layers turned into the sky of data.frame
let drawnKey = null; // what the last drawing showed (see baseKey and overlayKey)
let pending = false;
let report = { clickable: [] };
let setFovText = () => {};

const palette = () => (document.body.classList.contains("night") ? palettes.night : palettes.day);

// The J2000 layers in the current frame, rebuilt when a new frame or new data arrives.
function skyCache() {
  if (!data.frame) return null;
  if (cache && cache.frame === data.frame && cache.counts === countData()) return cache;
  const f = makeFrame(data.frame);
  const to = ([ra, dec]) => f.toSky(ra, dec);
  cache = {
    frame: data.frame,
    counts: countData(),
    toSky: f.toSky,
    toJ2000Vector: f.toJ2000Vector,
    lines: sky.lines.map(([abbr, lines]) => [abbr, lines.map((line) => line.map(to))]),
    names: sky.names.map(([abbr, name, ra, dec, rank]) => [abbr, name, f.toSky(ra, dec), rank]),
    milkyway: sky.milkyway.map((polygons) => polygons.map((polygon) => polygon.map((ring) => ring.map(to)))),
  };
  return cache;
}
const countData = () => `${sky.stars.length}/${sky.lines.length}/${sky.milkyway.length}/${sky.deepsky.length}`;

function resize() {
  const canvas = chart.canvas;
  const width = canvas.clientWidth || 600;
  const height = canvas.clientHeight || width;
  const ratio = window.devicePixelRatio || 1;
  if (canvas.width !== Math.round(width * ratio) || canvas.height !== Math.round(height * ratio)) {
    canvas.width = Math.round(width * ratio); canvas.height = Math.round(height * ratio);
  }
  chart.ctx.setTransform(ratio, 0, 0, ratio, 0, 0);
  chart.width = width; chart.height = height;
  schedule(true);
}

// The projection and helpers of the current view.
function scene() {
  const { width, height } = chart;
  const k = width / 2 / Math.tan((view.fov / 4) * RAD); // d3's stereographic: r = k·tan(θ/2)
  const clip = Math.min(100, view.fov * 0.75 + 1);
  const make = (precision) => d3.geoStereographic().reflectX(true).rotate([view.az, -view.alt, 0])
    .scale(k).translate([width / 2, height / 2]).clipAngle(clip)
    .clipExtent([[-2, -2], [width + 2, height + 2]]).precision(precision);
  const projection = make(0.4);
  const centre = skyPoint(view.alt, view.az);
  const centreVector = lonLatVector(centre);
  const cosLimit = Math.cos(clip * RAD);
  const c = palette();
  const s = {
    ctx: chart.ctx, width, height, projection, c, fov: view.fov, pxPerDeg: (k * RAD) / 2, centre, clip,
    path: d3.geoPath(projection, chart.ctx),
    // Without adaptive resampling, for dense outlines (the Milky Way): twice as fast.
    rough: make(0),
    sunAlt: data.state && data.state.sun ? data.state.sun.alt : null,
    twilight: data.twilight, // the server's boundaries (web/almanac.py), {phase: degrees}
    project: (p) => projection(p),
    // Screen position of a [lon, lat] point (v: its unit vector, if known), or null when off the view.
    screen(p, v = null) {
      const u = v || lonLatVector(p);
      if (u[0] * centreVector[0] + u[1] * centreVector[1] + u[2] * centreVector[2] < cosLimit) return null;
      const xy = projection(p);
      if (!xy || xy[0] < -SCREEN_MARGIN_PX || xy[1] < -SCREEN_MARGIN_PX
        || xy[0] > width + SCREEN_MARGIN_PX || xy[1] > height + SCREEN_MARGIN_PX) return null;
      return xy;
    },
    // The screen angle of celestial north at a J2000 object (for galaxies' position angles).
    northAngle(obj, p) {
      const a = projection(p), b = projection(cache.toSky(obj.ra, Math.min(obj.dec + 0.05, 89.99)));
      return Math.atan2(b[1] - a[1], b[0] - a[0]);
    },
  };
  return s;
}

// What the base layers (the sky, its objects, the ground, the limits, the Sun's zone) depend
// on, rounded to what would move a pixel: they are drawn again only when this changes, into an
// off-screen canvas that every drawing copies before the markers and labels.
function baseKey(s) {
  const step = 0.3 / s.pxPerDeg; // degrees per third of a pixel
  const r = (v) => (v == null ? "-" : Math.round(v / step));
  const sun = (data.state && data.state.sun) || {};
  const zenith = data.frame ? data.frame.zenith : [null, null];
  const limits = data.mount && data.mount.limits;
  return [
    view.alt, view.az, view.fov, chart.width, chart.height, s.c === palettes.night, r(zenith[0]), r(zenith[1]),
    Math.round((sun.alt || 0) * 4), r(sun.alt), r(sun.az), sun.radius_deg, countData(), data.sky.length,
    limits ? JSON.stringify(limits.horizon) + limits.max_altitude_deg : "", data.twilight ? 1 : 0,
  ].join("|");
}

// ... and what the markers depend on: a 4 Hz update of a mount standing still draws nothing.
function overlayKey(s) {
  const step = 0.3 / s.pxPerDeg;
  const r = (v) => (v == null ? "-" : Math.round(v / step));
  const st = data.state || {};
  const t = st.target_altaz || {};
  return [
    r(st.alt_deg), r(st.az_deg), r(t.alt), r(t.az), st.slewing, JSON.stringify(data.selected),
    JSON.stringify(chart.field), data.track ? data.track.path.length + String(data.track.error_arcsec) : "",
  ].join("|");
}

function schedule(force = false) {
  if (force) { drawnKey = null; base.key = null; }
  if (pending || !chart.ctx) return;
  pending = true;
  requestAnimationFrame(() => { pending = false; draw(); });
}

const base = { key: null, canvas: document.createElement("canvas"), labels: [], clickable: [], drawn: {} };

function drawBase(s) {
  const ratio = window.devicePixelRatio || 1;
  const canvas = base.canvas;
  canvas.width = chart.canvas.width; canvas.height = chart.canvas.height;
  const ctx = canvas.getContext("2d");
  ctx.setTransform(ratio, 0, 0, ratio, 0, 0);
  const b = { ...s, ctx, path: d3.geoPath(s.projection, ctx), roughPath: d3.geoPath(s.rough, ctx) };
  const layers = skyCache();
  drawBackground(b);
  const drawn = { milkyway: 0, constellations: 0, stars: 0, deepsky: 0, named: 0 };
  let labels = drawGrid(b), clickable = [];
  if (layers) {
    drawn.milkyway = drawMilkyWay(b, layers.milkyway);
    const constellations = drawConstellations(b, layers.lines, layers.names);
    drawn.constellations = constellations.count;
    labels = labels.concat(constellations.labels);
    // Stars and deep-sky objects: only those near the view are turned into the sky of now.
    const near = { centre: layers.toJ2000Vector(s.centre), cos: Math.cos(s.clip * RAD + RAD), toSky: layers.toSky };
    drawn.stars = drawStars(b, sky.stars, sky.starVectors, near);
    const dso = drawDeepSky(b, sky.deepsky, near);
    drawn.deepsky = dso.count; labels = labels.concat(dso.labels); clickable = clickable.concat(dso.clickable);
  }
  drawGround(b);
  drawLimits(b, data.mount && data.mount.limits);
  drawn.sunZone = drawSunZone(b, data.state && data.state.sun);
  const named = drawNamedObjects(b, data.sky);
  drawn.named = named.count; labels = labels.concat(named.labels); clickable = clickable.concat(named.clickable);
  Object.assign(base, { labels, clickable, drawn });
}

function draw() {
  const s = scene();
  const keys = [baseKey(s), overlayKey(s)];
  const key = keys.join("#");
  if (key === drawnKey) return;
  drawnKey = key;
  const started = performance.now();
  const { ctx, width, height } = s;
  if (base.key !== keys[0]) { drawBase(s); base.key = keys[0]; }
  ctx.save(); ctx.setTransform(1, 0, 0, 1, 0, 0);
  ctx.clearRect(0, 0, chart.canvas.width, chart.canvas.height); ctx.drawImage(base.canvas, 0, 0);
  ctx.restore();
  const paths = drawPaths(s, data.state, data.mount, data.track, skyCache());
  const markers = drawMarkers(s, data.state, where(), chart.field, data.track);
  const budget = Math.max(8, Math.round((width * height) / LABEL_AREA_PX2));
  const placed = placeLabels(ctx, base.labels, markers.keepOut, width, height, budget);
  const fovText = view.fov >= 10 ? `${view.fov.toFixed(0)}°` : `${view.fov.toFixed(1)}°`;
  // The phase is the server's (web/almanac.py: one definition of its boundaries); kept between
  // messages that carry no clock.
  if (data.state && data.state.clock && data.state.clock.twilight) chart.twilight = data.state.clock.twilight;
  const twilight = chart.twilight || "";
  setFovText(`${fovText}${twilight ? ` · ${twilight}` : ""}`);
  report = {
    ...base.drawn, ...paths, ...markers.result, labels: placed, clickable: base.clickable, fov: view.fov,
    view: { alt: view.alt, az: view.az }, twilight, ms: performance.now() - started,
  };
}

// Where a selection is: {alt, az} (observed), or null when its object is not on the chart.
function where(selection = data.selected) {
  if (!selection) return null;
  if (!selection.name) return selection;
  const obj = data.sky.find((o) => o.name === selection.name);
  if (obj) return { alt: obj.alt, az: obj.az };
  const layers = skyCache();
  const dso = layers && sky.deepsky.find((o) => o.name === selection.name);
  return dso ? altAz(layers.toSky(dso.ra, dso.dec)) : null;
}

// A click at (x, y) in CSS pixels: the nearest object within reach, or that point of the sky.
function selectAt(x, y) {
  let best = null, bestDistance = CLICK_RADIUS_PX;
  for (const obj of report.clickable) {
    const d = Math.hypot(obj.x - x, obj.y - y);
    if (d < bestDistance) { best = obj; bestDistance = d; }
  }
  if (best) { hooks.onSelect({ name: best.name }); return; }
  const p = scene().projection.invert([x, y]);
  if (!p || !Number.isFinite(p[0])) return;
  const point = altAz(p);
  if (point.alt < -10) return;
  hooks.onSelect(point);
}

// While a target is followed its error changes: GET /api/track again every few seconds (the
// server keeps the path for 30 s and the last error at hand, so a request is cheap); a new
// target asks at once. The serial drops answers and timers a later request made stale.
const TRACK_REFRESH_MS = 5000;
let trackSerial = 0;
async function refreshTrack() {
  const serial = ++trackSerial;
  const track = await loadTrack();
  if (serial !== trackSerial) return;
  data.track = track;
  schedule();
  if (track && track.target) {
    setTimeout(() => { if (serial === trackSerial) refreshTrack(); }, TRACK_REFRESH_MS);
  }
}
const mountAltAz = () => (data.state && data.state.alt_deg != null ? { alt: data.state.alt_deg, az: data.state.az_deg } : null);
const targetKey = (state) => (state && state.target ? JSON.stringify(state.target) : "");

const Chart = {
  // canvas: the <canvas>; options.onSelect(selection) gets {name} or {alt, az}.
  init(canvas, options = {}) {
    chart.canvas = canvas;
    chart.ctx = canvas.getContext("2d");
    if (options.onSelect) hooks.onSelect = options.onSelect;
    const actions = attachControls({
      canvas, redraw: () => schedule(), scene, select: selectAt,
      mountAltAz,
    });
    setFovText = buildToolbar(canvas, actions, chart.field, () => schedule());
    window.addEventListener("resize", resize);
    resize();
    loadSky(() => schedule());
    refreshTrack();
  },
  // Any of {mount, state, sky, frame, twilight} from the live connection; draws if that changes the view.
  update(changes) {
    const before = targetKey(data.state);
    for (const key of ["mount", "state", "sky", "frame", "twilight"]) if (changes[key] !== undefined) data[key] = changes[key];
    if (targetKey(data.state) !== before) refreshTrack(); // a new target may have a new track
    if (chart.ctx) followMount(mountAltAz(), FOLLOW_STEP_PX / scene().pxPerDeg);
    schedule();
  },
  // The selection to ring (null for none).
  select(selection) { data.selected = selection; schedule(); },
  where,
  // Draw again (after the night mode changed the palette).
  redraw: () => schedule(true),
  // For tests and debugging: the projection (CSS pixels on the canvas), the context, what the
  // last drawing showed (counts, label boxes, the frame, the time it took) and the objects.
  debug: {
    project: (alt, az) => scene().projection(skyPoint(alt, az)),
    get ctx() { return chart.ctx; },
    get size() { return chart.width; },
    report: () => report,
    // The faintest magnitude the sky lets through with the Sun at `sunAlt` (the server's twilight).
    skyLimit: (sunAlt) => skyLimit(sunAlt, data.twilight),
    // The mean time of `n` full drawings (sky layers included), in milliseconds.
    benchmark(n = 5) {
      const started = performance.now();
      for (let i = 0; i < n; i++) { drawnKey = null; base.key = null; draw(); }
      return (performance.now() - started) / n;
    },
    view,
    find: (name) => data.sky.find((o) => o.name === name) || null,
    // A J2000 position as the chart places it now ({alt, az}), or null without a frame.
    toSky: (ra, dec) => { const layers = skyCache(); return layers ? altAz(layers.toSky(ra, dec)) : null; },
  },
};
window.Chart = Chart;
