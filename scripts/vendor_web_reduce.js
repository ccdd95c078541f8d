// Reduce d3-celestial's data to what the dashboard's sky chart draws, at the precision it needs
// (scripts/vendor_web.sh runs this; docs/dashboard.md, "Sky chart"):
//   stars.json           [ra, dec, mag, ra, dec, mag, ...] to magnitude 7.5, 0.001° (3.6″)
//   constellations.json  {lines: [[abbr, [[[ra, dec], ...], ...]], ...],
//                         names: [[abbr, name, ra, dec, rank], ...]}, 0.01°
//   milkyway.json        {levels: [MultiPolygon coordinates, ...]} from faint to bright, 0.1°,
//                        vertices closer than 0.15° dropped, every ring wound so that d3-geo
//                        takes its inside to be the smaller side
// RA is in degrees 0-360 everywhere (d3-celestial writes -180..180).
"use strict";

const fs = require("fs");
const path = require("path");
const vm = require("vm");

const [work, out] = process.argv.slice(2);
const data = (name) =>
  JSON.parse(fs.readFileSync(path.join(work, "d3-celestial/package/data", name), "utf8"));

// d3-geo's UMD build, run with d3-array in a bare context, for geoArea.
const context = vm.createContext({});
for (const file of ["d3-array/package/dist/d3-array.min.js", "d3-geo/package/dist/d3-geo.min.js"]) {
  vm.runInContext(fs.readFileSync(path.join(work, file), "utf8"), context);
}
const d3 = context.d3;

const STAR_LIMIT = 7.5; // the faintest star kept (magnitude)
const round = (value, decimals) => Number(value.toFixed(decimals));
const ra360 = (ra) => (ra < 0 ? ra + 360 : ra);
const point = ([ra, dec], decimals) => [round(ra360(ra), decimals), round(dec, decimals)];

function write(name, value) {
  const text = JSON.stringify(value);
  fs.writeFileSync(path.join(out, name), text + "\n");
  console.log(`${name}: ${text.length} bytes`);
}

// Stars: brightest first, so that the chart can stop early when zoomed out; one flat array.
const stars = data("stars.8.json").features
  .filter((f) => f.properties.mag <= STAR_LIMIT)
  .map((f) => [...point(f.geometry.coordinates, 3), round(Number(f.properties.mag), 2)])
  .sort((a, b) => a[2] - b[2]);
write("stars.json", stars.flat());

const lines = data("constellations.lines.json").features.map((f) => [
  f.id,
  f.geometry.coordinates.map((line) => line.map((p) => point(p, 2))),
]);
const names = data("constellations.json").features.map((f) => [
  f.id,
  f.properties.name,
  ...point(f.geometry.coordinates, 2),
  Number(f.properties.rank),
]);
write("constellations.json", { lines, names });

function thin(ring) {
  const kept = [];
  for (const p of ring) {
    const q = point(p, 1);
    const last = kept[kept.length - 1];
    if (last && Math.abs(last[0] - q[0]) < 0.15 && Math.abs(last[1] - q[1]) < 0.15) continue;
    kept.push(q);
  }
  if (kept.length && (kept[0][0] !== kept[kept.length - 1][0] || kept[0][1] !== kept[kept.length - 1][1])) {
    kept.push(kept[0]);
  }
  return kept;
}

const levels = data("mw.json").features.map((f) =>
  f.geometry.coordinates
    .map((polygon) => polygon.map(thin).filter((ring) => ring.length >= 4))
    .filter((polygon) => polygon.length)
    .map((polygon) => {
      const area = d3.geoArea({ type: "Polygon", coordinates: polygon });
      return area > 2 * Math.PI ? polygon.map((ring) => ring.slice().reverse()) : polygon;
    }),
);
write("milkyway.json", { levels });
