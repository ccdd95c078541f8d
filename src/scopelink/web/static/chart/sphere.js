// Coordinates of the sky chart. The chart works in horizontal coordinates as d3-geo wants them:
// [lon, lat] in degrees with lon = −azimuth and lat = altitude (a right-handed frame: north,
// west, up), so that d3 treats every edge as a great-circle arc and every polygon by its
// winding. J2000 data (constellations, Milky Way, stars, deep-sky objects) is turned into that
// frame by the rotation the server sends with the sky (`sky_frame`: the J2000 directions of the
// zenith and of a point of the north meridian, computed by ERFA), plus refraction, added here.
"use strict";

export const RAD = Math.PI / 180;

export function unit(raDeg, decDeg) {
  const ra = raDeg * RAD, dec = decDeg * RAD;
  return [Math.cos(dec) * Math.cos(ra), Math.cos(dec) * Math.sin(ra), Math.sin(dec)];
}

const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
function normalise(v) {
  const n = Math.hypot(v[0], v[1], v[2]);
  return [v[0] / n, v[1] / n, v[2] / n];
}

// Refraction in degrees for a true altitude (Sæmundsson's formula, standard air), continued
// flat below −1° so that the ground stays smooth. The server's objects come refracted by ERFA;
// the two agree to well under an arcminute above 5° of altitude.
export function refraction(altDeg) {
  const h = Math.max(altDeg, -1);
  return (1.02 / Math.tan((h + 10.3 / (h + 5.11)) * RAD)) / 60;
}

// The rotation J2000 -> horizontal of one moment; `frame` is the server's sky_frame.
export function makeFrame(frame) {
  const up = unit(frame.zenith[0], frame.zenith[1]);
  const meridian = unit(frame.north[0], frame.north[1]);
  const along = dot(meridian, up);
  const north = normalise([meridian[0] - along * up[0], meridian[1] - along * up[1], meridian[2] - along * up[2]]);
  const west = cross(up, north);
  return {
    // A horizontal [lon, lat] -> its J2000 unit vector (refraction left aside: for culling).
    toJ2000Vector(p) {
      const [x, y, z] = unit(p[0], p[1]);
      return [0, 1, 2].map((i) => x * north[i] + y * west[i] + z * up[i]);
    },
    // J2000 RA, Dec (degrees) -> [lon, lat] seen from the site, refracted.
    toSky(raDeg, decDeg) {
      const v = unit(raDeg, decDeg);
      const alt = Math.asin(Math.max(-1, Math.min(1, dot(v, up)))) / RAD;
      return [Math.atan2(dot(v, west), dot(v, north)) / RAD, alt + refraction(alt)];
    },
  };
}

export const skyPoint = (alt, az) => [-az, alt];
export const lonLatVector = ([lon, lat]) => unit(lon, lat);
export function altAz([lon, lat]) {
  let az = -lon % 360;
  if (az < 0) az += 360;
  return { alt: lat, az };
}

// Altitude/azimuth <-> hour angle/declination (degrees) at latitude `lat` (geometric).
export function altAzToHaDec(alt, az, lat) {
  const a = alt * RAD, z = az * RAD, p = lat * RAD;
  const sinDec = Math.sin(a) * Math.sin(p) + Math.cos(a) * Math.cos(p) * Math.cos(z);
  const dec = Math.asin(Math.max(-1, Math.min(1, sinDec)));
  const ha = Math.atan2(-Math.sin(z) * Math.cos(a), Math.sin(a) * Math.cos(p) - Math.cos(a) * Math.sin(p) * Math.cos(z));
  return { ha: ha / RAD, dec: dec / RAD };
}

export function haDecToAltAz(ha, dec, lat) {
  const h = ha * RAD, d = dec * RAD, p = lat * RAD;
  const sinAlt = Math.sin(d) * Math.sin(p) + Math.cos(d) * Math.cos(p) * Math.cos(h);
  const alt = Math.asin(Math.max(-1, Math.min(1, sinAlt)));
  const az = Math.atan2(-Math.sin(h) * Math.cos(d), Math.sin(d) * Math.cos(p) - Math.cos(d) * Math.sin(p) * Math.cos(h));
  return { alt: alt / RAD, az: ((az / RAD) + 360) % 360 };
}

const wrap180 = (deg) => ((((deg + 180) % 360) + 360) % 360) - 180;

// The route the mount's axes take from `from` to `to` ({alt, az}), both axes driven at the same
// speed, each stopping when it arrives (how SynScan mounts slew): linear in azimuth and altitude
// on an alt-az mount, in hour angle and declination on an equatorial one, the short way round
// the primary axis. Returned as [lon, lat] points for d3.
export function axisPath(from, to, alignment, lat, steps = 48) {
  const polar = alignment !== "altaz";
  const a = polar ? altAzToHaDec(from.alt, from.az, lat) : { ha: from.az, dec: from.alt };
  const b = polar ? altAzToHaDec(to.alt, to.az, lat) : { ha: to.az, dec: to.alt };
  const d1 = wrap180(b.ha - a.ha), d2 = b.dec - a.dec;
  const longest = Math.max(Math.abs(d1), Math.abs(d2)) || 1;
  const points = [];
  for (let i = 0; i <= steps; i++) {
    const travelled = (longest * i) / steps;
    const p1 = a.ha + Math.sign(d1) * Math.min(travelled, Math.abs(d1));
    const p2 = a.dec + Math.sign(d2) * Math.min(travelled, Math.abs(d2));
    const where = polar ? haDecToAltAz(p1, p2, lat) : { alt: p2, az: p1 };
    points.push(skyPoint(where.alt, where.az));
  }
  return points;
}
