// scopelink sky chart: draws the sky, the limits, the Sun's zone and the mount on the page's
// canvas. app.js talks to it only through the small interface at the end (window.Chart); the
// chart draws only when something changes (new data, an interaction), never in a loop.
"use strict";

const Chart = (() => {
  const LOWEST_ALT = -10; // the chart shows a little below the horizon, where limits may lie
  const data = { mount: null, state: null, sky: [], selected: null };
  const hooks = { onSelect: () => {} };

  const palettes = {
    day: {
      sky: "#06101f", grid: "#22324d", horizon: "#5b6b86", limit: "rgba(217,83,79,0.22)",
      limitEdge: "#d9534f", star: "#e8eefc", below: "#3a4458", label: "#9fb0cc",
      planet: "#ffd27f", moon: "#f4f4f4", sun: "#ffb000", mount: "#5fa8ff", target: "#4caf50",
      selected: "#ff7ad9",
    },
    night: {
      sky: "#000000", grid: "#2a0000", horizon: "#5a0a0a", limit: "rgba(120,0,0,0.35)",
      limitEdge: "#7a1010", star: "#d02020", below: "#3a0505", label: "#8a1515",
      planet: "#e03030", moon: "#e03030", sun: "#e03030", mount: "#ff3030", target: "#b01a1a",
      selected: "#ff5050",
    },
  };
  const palette = () => (document.body.classList.contains("night") ? palettes.night : palettes.day);

  const chart = {
    canvas: null, ctx: null, size: 0, cx: 0, cy: 0, radius: 0,
    // Stereographic: zenith at the centre, the horizon at `radius`; north up, east left (the
    // sky seen from below, as on a planisphere).
    project(alt, az) {
      const r = this.radius * Math.tan(((90 - alt) * Math.PI) / 360);
      const a = (az * Math.PI) / 180;
      return [this.cx - r * Math.sin(a), this.cy - r * Math.cos(a)];
    },
    unproject(x, y) {
      const dx = this.cx - x, dy = this.cy - y;
      const r = Math.hypot(dx, dy) / this.radius;
      const alt = 90 - (360 / Math.PI) * Math.atan(r);
      let az = (Math.atan2(dx, dy) * 180) / Math.PI;
      if (az < 0) az += 360;
      return [alt, az];
    },
  };

  function resizeChart() {
    const canvas = chart.canvas;
    const cssSize = canvas.clientWidth || 600;
    const ratio = window.devicePixelRatio || 1;
    const pixels = Math.round(cssSize * ratio);
    if (canvas.width !== pixels) { canvas.width = pixels; canvas.height = pixels; }
    chart.ctx.setTransform(ratio, 0, 0, ratio, 0, 0);
    chart.size = cssSize;
    chart.cx = chart.cy = cssSize / 2;
    // Leave room for the band below the horizon down to LOWEST_ALT and the compass letters.
    chart.radius = (cssSize / 2 - 16) / Math.tan(((90 - LOWEST_ALT) * Math.PI) / 360);
    drawChart();
  }

  function starRadius(mag) {
    if (mag == null) return 3;
    return Math.max(0.8, Math.min(4.5, 3.6 - 0.75 * mag));
  }

  function objectStyle(obj, colours) {
    switch (obj.kind) {
      case "sun": return { colour: colours.sun, radius: 7, label: true };
      case "moon": return { colour: colours.moon, radius: 6, label: true };
      case "planet":
      case "dwarf planet": return { colour: colours.planet, radius: 3.5, label: obj.kind === "planet" };
      default: return { colour: colours.star, radius: starRadius(obj.mag), label: obj.mag != null && obj.mag < 1.0 };
    }
  }

  function drawChart() {
    const ctx = chart.ctx;
    if (!ctx) return;
    const c = palette();
    const { cx, cy, radius, size } = chart;
    ctx.clearRect(0, 0, size, size);
    const outer = chart.project(LOWEST_ALT, 0)[1];
    const edge = cy - outer;
    ctx.fillStyle = c.sky;
    ctx.beginPath(); ctx.arc(cx, cy, edge, 0, 2 * Math.PI); ctx.fill();

    // Forbidden sky: below the horizon limit (profile by azimuth) and above the maximum altitude.
    const limits = data.mount && data.mount.limits;
    if (limits) {
      ctx.fillStyle = c.limit;
      ctx.beginPath();
      ctx.arc(cx, cy, edge, 0, 2 * Math.PI);
      const outline = limits.horizon.concat([limits.horizon[0]]);
      outline.forEach(([az, alt], i) => {
        const [x, y] = chart.project(Math.max(alt, LOWEST_ALT), az);
        if (i === 0) ctx.moveTo(x, y); else ctx.lineTo(x, y);
      });
      ctx.fill("evenodd");
      ctx.strokeStyle = c.limitEdge; ctx.lineWidth = 1.2; ctx.stroke();
      if (limits.max_altitude_deg < 90) {
        const r = cy - chart.project(limits.max_altitude_deg, 0)[1];
        ctx.beginPath(); ctx.arc(cx, cy, r, 0, 2 * Math.PI); ctx.fill(); ctx.stroke();
      }
    }

    drawSunZone(ctx, c);

    // Altitude circles every 30°, the horizon, azimuth spokes every 45°.
    ctx.strokeStyle = c.grid; ctx.lineWidth = 1;
    for (const alt of [30, 60]) {
      const r = cy - chart.project(alt, 0)[1];
      ctx.beginPath(); ctx.arc(cx, cy, r, 0, 2 * Math.PI); ctx.stroke();
    }
    for (let az = 0; az < 360; az += 45) {
      const [x, y] = chart.project(0, az);
      ctx.beginPath(); ctx.moveTo(cx, cy); ctx.lineTo(x, y); ctx.stroke();
    }
    ctx.strokeStyle = c.horizon; ctx.lineWidth = 1.5;
    ctx.beginPath(); ctx.arc(cx, cy, radius, 0, 2 * Math.PI); ctx.stroke();
    ctx.fillStyle = c.label; ctx.font = "bold 13px system-ui, sans-serif";
    ctx.textAlign = "center"; ctx.textBaseline = "middle";
    for (const [letter, az] of [["N", 0], ["E", 90], ["S", 180], ["W", 270]]) {
      const r = edge + 9;
      const a = (az * Math.PI) / 180;
      ctx.fillText(letter, cx - r * Math.sin(a), cy - r * Math.cos(a));
    }

    // Objects: dim below the horizon, labels for the brightest.
    ctx.font = "11px system-ui, sans-serif"; ctx.textAlign = "left";
    for (const obj of data.sky) {
      if (obj.alt < LOWEST_ALT) continue;
      const [x, y] = chart.project(obj.alt, obj.az);
      const style = objectStyle(obj, c);
      ctx.fillStyle = obj.alt < 0 ? c.below : style.colour;
      ctx.beginPath(); ctx.arc(x, y, style.radius, 0, 2 * Math.PI); ctx.fill();
      if (style.label && obj.alt >= 0) {
        ctx.fillStyle = c.label;
        ctx.fillText(obj.name, x + style.radius + 3, y);
      }
    }

    // The selection, the target and where the mount points.
    const sel = selectedPosition();
    if (sel) {
      const [x, y] = chart.project(sel.alt, sel.az);
      ctx.strokeStyle = c.selected; ctx.lineWidth = 2;
      ctx.beginPath(); ctx.arc(x, y, 10, 0, 2 * Math.PI); ctx.stroke();
    }
    const state = data.state;
    if (state && state.target_altaz && state.target_altaz.alt >= LOWEST_ALT) {
      const [x, y] = chart.project(state.target_altaz.alt, state.target_altaz.az);
      ctx.strokeStyle = c.target; ctx.lineWidth = 2;
      ctx.strokeRect(x - 7, y - 7, 14, 14);
    }
    if (state && state.alt_deg != null && state.alt_deg >= LOWEST_ALT) {
      const [x, y] = chart.project(state.alt_deg, state.az_deg);
      ctx.strokeStyle = c.mount; ctx.lineWidth = 2;
      ctx.beginPath(); ctx.arc(x, y, 9, 0, 2 * Math.PI); ctx.stroke();
      ctx.beginPath();
      ctx.moveTo(x - 15, y); ctx.lineTo(x - 5, y); ctx.moveTo(x + 5, y); ctx.lineTo(x + 15, y);
      ctx.moveTo(x, y - 15); ctx.lineTo(x, y - 5); ctx.moveTo(x, y + 5); ctx.lineTo(x, y + 15);
      ctx.stroke();
    }
  }

  // The Sun avoidance zone: the small circle `radius_deg` around the Sun, filled like the limits.
  function drawSunZone(ctx, c) {
    const sun = data.state && data.state.sun;
    if (!sun || !(sun.radius_deg > 0)) return;
    const rad = Math.PI / 180;
    const d = sun.radius_deg * rad, alt0 = sun.alt * rad, az0 = sun.az * rad;
    ctx.fillStyle = c.limit; ctx.strokeStyle = c.limitEdge; ctx.lineWidth = 1.2;
    ctx.beginPath();
    for (let bearing = 0; bearing <= 360; bearing += 5) {
      const b = bearing * rad;
      const alt = Math.asin(Math.sin(alt0) * Math.cos(d) + Math.cos(alt0) * Math.sin(d) * Math.cos(b));
      const az = az0 + Math.atan2(Math.sin(b) * Math.sin(d) * Math.cos(alt0),
        Math.cos(d) - Math.sin(alt0) * Math.sin(alt));
      const [x, y] = chart.project(Math.max(alt / rad, LOWEST_ALT), az / rad);
      if (bearing === 0) ctx.moveTo(x, y); else ctx.lineTo(x, y);
    }
    ctx.closePath(); ctx.fill(); ctx.stroke();
  }

  function selectedPosition() {
    const sel = data.selected;
    if (!sel) return null;
    if (sel.name) {
      const obj = data.sky.find((o) => o.name === sel.name);
      return obj ? { alt: obj.alt, az: obj.az } : null;
    }
    return sel;
  }

  function objectAt(x, y) {
    let best = null, bestDistance = 18; // px: a finger-sized target
    for (const obj of data.sky) {
      if (obj.alt < LOWEST_ALT) continue;
      const [ox, oy] = chart.project(obj.alt, obj.az);
      const d = Math.hypot(ox - x, oy - y);
      if (d < bestDistance) { best = obj; bestDistance = d; }
    }
    return best;
  }

  function onChartClick(event) {
    const rect = chart.canvas.getBoundingClientRect();
    const x = ((event.clientX - rect.left) / rect.width) * chart.size;
    const y = ((event.clientY - rect.top) / rect.height) * chart.size;
    const obj = objectAt(x, y);
    if (obj) {
      hooks.onSelect({ name: obj.name });
      return;
    }
    const [alt, az] = chart.unproject(x, y);
    if (alt < LOWEST_ALT) return;
    hooks.onSelect({ alt, az });
  }

  return {
    // canvas: the <canvas>; options.onSelect(selection) is called with {name} or {alt, az}.
    init(canvas, options = {}) {
      chart.canvas = canvas;
      chart.ctx = canvas.getContext("2d");
      if (options.onSelect) hooks.onSelect = options.onSelect;
      window.addEventListener("resize", resizeChart);
      canvas.addEventListener("click", onChartClick);
      resizeChart();
    },
    // Any of {mount, state, sky} from the live connection; redraws once.
    update(changes) {
      for (const key of ["mount", "state", "sky"]) if (changes[key] !== undefined) data[key] = changes[key];
      drawChart();
    },
    // The selection to ring (null for none).
    select(selection) { data.selected = selection; drawChart(); },
    // Where a selection is now ({alt, az}), or null when its object is not on the chart.
    where: selectedPosition,
    // Draw again (after the night mode changed the palette).
    redraw: drawChart,
    // For tests and debugging: the projection (CSS pixels on the canvas), the context, and
    // the objects the chart knows.
    debug: {
      project: (alt, az) => chart.project(alt, az),
      get ctx() { return chart.ctx; },
      get size() { return chart.size; },
      find: (name) => data.sky.find((o) => o.name === name) || null,
    },
  };
})();
window.Chart = Chart;
