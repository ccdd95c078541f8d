// Labels that never overlap: a greedy placement. Candidates come with a priority (lower first:
// the Sun, Moon and planets, then by magnitude); each tries eight places around its symbol
// (right, left, above, below, then the diagonals) and takes the first whose box hits no box
// already taken and stays on the canvas; one that fits nowhere is not drawn. Boxes of symbols that must stay
// readable (the mount, the target) are taken before any label.
"use strict";

const PAD = 2; // px kept clear around each label

const hits = (a, b) => a[0] < b[2] && b[0] < a[2] && a[1] < b[3] && b[1] < a[3];

// A grid of buckets so that each test looks at the few boxes nearby, not at all of them.
class Boxes {
  constructor(cell = 64) { this.cell = cell; this.buckets = new Map(); this.all = []; }
  keys(box) {
    const keys = [];
    const c = this.cell;
    for (let i = Math.floor(box[0] / c); i <= Math.floor(box[2] / c); i++) {
      for (let j = Math.floor(box[1] / c); j <= Math.floor(box[3] / c); j++) keys.push(`${i},${j}`);
    }
    return keys;
  }
  free(box) {
    for (const key of this.keys(box)) {
      const bucket = this.buckets.get(key);
      if (bucket && bucket.some((other) => hits(box, other))) return false;
    }
    return true;
  }
  add(box) {
    this.all.push(box);
    for (const key of this.keys(box)) {
      if (!this.buckets.has(key)) this.buckets.set(key, []);
      this.buckets.get(key).push(box);
    }
  }
}

// candidates: [{text, x, y, r, priority, font, colour}]; keepOut: boxes [x0, y0, x1, y1].
// Draws the labels that fit and returns them as {text, box} (box without the padding).
export function placeLabels(ctx, candidates, keepOut, width, height, budget) {
  const taken = new Boxes();
  for (const box of keepOut) taken.add(box);
  const placed = [];
  const sorted = candidates.slice().sort((a, b) => a.priority - b.priority);
  ctx.textBaseline = "alphabetic";
  ctx.textAlign = "left";
  for (const label of sorted) {
    if (placed.length >= budget) break;
    ctx.font = label.font;
    const w = ctx.measureText(label.text).width;
    const h = label.size;
    const gap = label.r + 3;
    const spots = [
      [label.x + gap, label.y - h / 2], // right
      [label.x - gap - w, label.y - h / 2], // left
      [label.x - w / 2, label.y - gap - h], // above
      [label.x - w / 2, label.y + gap], // below
      [label.x + gap * 0.8, label.y - gap * 0.8 - h], // above right
      [label.x + gap * 0.8, label.y + gap * 0.8], // below right
      [label.x - gap * 0.8 - w, label.y - gap * 0.8 - h], // above left
      [label.x - gap * 0.8 - w, label.y + gap * 0.8], // below left
    ];
    for (const [x, y] of spots) {
      const box = [x - PAD, y - PAD, x + w + PAD, y + h + PAD];
      if (box[0] < 0 || box[1] < 0 || box[2] > width || box[3] > height || !taken.free(box)) continue;
      taken.add(box);
      ctx.fillStyle = label.colour;
      ctx.fillText(label.text, x, y + h * 0.8);
      placed.push({ text: label.text, box: [x, y, x + w, y + h] });
      break;
    }
  }
  return placed;
}
