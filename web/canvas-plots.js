// The density pictures drawn straight from typed arrays into canvases: the heat strip (a
// method's marginal density over time) and the 2-D heatmap (the joint density now), each with
// axes, ticks and a numeric colour bar, sized to its panel.

// A perceptually ordered blue → green → yellow scale (viridis-like stops).
const STOPS = [[68, 1, 84], [59, 82, 139], [33, 145, 140], [94, 201, 98], [253, 231, 37]];
export function colormap(v) {
  const x = Math.max(0, Math.min(1, v)) * (STOPS.length - 1);
  const i = Math.min(STOPS.length - 2, Math.floor(x));
  const f = x - i;
  return STOPS[i].map((c, k) => Math.round(c + f * (STOPS[i + 1][k] - c)));
}
export const rgb = (c) => `rgb(${c[0]},${c[1]},${c[2]})`;

const FONT = 12; // CSS px of tick labels (scaled up in presentation mode by the caller)

/** Sizes `canvas` to `width × height` CSS pixels at the screen's pixel density. */
export function sizeCanvas(canvas, width, height) {
  const dpr = window.devicePixelRatio || 1;
  const w = Math.max(1, Math.round(width * dpr));
  const h = Math.max(1, Math.round(height * dpr));
  if (canvas.width !== w || canvas.height !== h) {
    canvas.width = w;
    canvas.height = h;
  }
  canvas.style.width = `${width}px`;
  canvas.style.height = `${height}px`;
  return dpr;
}

/** About `count` round tick values within [lo, hi]. */
export function ticks(lo, hi, count = 5) {
  if (!(hi > lo)) return [lo];
  const raw = (hi - lo) / count;
  const mag = 10 ** Math.floor(Math.log10(raw));
  const step = [1, 2, 2.5, 5, 10].map((m) => m * mag).find((s) => s >= 0.7 * raw) ?? 10 * mag;
  const out = [];
  for (let v = Math.ceil(lo / step) * step; v <= hi + 1e-9 * step; v += step) out.push(Math.abs(v) < 1e-12 * step ? 0 : v);
  return out;
}

const fmt = (v) => {
  const a = Math.abs(v);
  if (a !== 0 && (a < 1e-3 || a >= 1e5)) return v.toExponential(1);
  return String(Number(v.toPrecision(4)));
};

/**
 * Axes around the plot box `b` ({x, y, w, h} in device pixels): ticks and labels of the
 * x range `[x0, x1]` below and the y range `[y0, y1]` on the left (y grows upwards).
 */
function axes(ctx, b, [x0, x1], [y0, y1], xLabel, yLabel, scale) {
  ctx.save();
  ctx.strokeStyle = '#333';
  ctx.fillStyle = '#333';
  ctx.lineWidth = scale;
  ctx.font = `${FONT * scale}px system-ui, sans-serif`;
  ctx.strokeRect(b.x, b.y, b.w, b.h);
  ctx.textAlign = 'center';
  ctx.textBaseline = 'top';
  for (const v of ticks(x0, x1, Math.max(3, Math.floor(b.w / (60 * scale))))) {
    const px = b.x + ((v - x0) / (x1 - x0)) * b.w;
    ctx.beginPath();
    ctx.moveTo(px, b.y + b.h);
    ctx.lineTo(px, b.y + b.h + 4 * scale);
    ctx.stroke();
    ctx.fillText(fmt(v), px, b.y + b.h + 5 * scale);
  }
  ctx.fillText(xLabel, b.x + b.w / 2, b.y + b.h + (7 + FONT) * scale);
  ctx.textAlign = 'right';
  ctx.textBaseline = 'middle';
  for (const v of ticks(y0, y1, Math.max(3, Math.floor(b.h / (36 * scale))))) {
    const py = b.y + b.h - ((v - y0) / (y1 - y0)) * b.h;
    ctx.beginPath();
    ctx.moveTo(b.x - 4 * scale, py);
    ctx.lineTo(b.x, py);
    ctx.stroke();
    ctx.fillText(fmt(v), b.x - 6 * scale, py);
  }
  ctx.translate(b.x - 34 * scale, b.y + b.h / 2);
  ctx.rotate(-Math.PI / 2);
  ctx.textAlign = 'center';
  ctx.textBaseline = 'bottom';
  ctx.fillText(yLabel, 0, 0);
  ctx.restore();
}

/** A vertical colour bar in box `b` from 0 to `max`, with numeric ticks and a title. */
function colourBar(ctx, b, max, title, scale) {
  const grad = ctx.createLinearGradient(0, b.y + b.h, 0, b.y);
  for (let k = 0; k <= 8; k++) grad.addColorStop(k / 8, rgb(colormap(k / 8)));
  ctx.save();
  ctx.fillStyle = grad;
  ctx.fillRect(b.x, b.y, b.w, b.h);
  ctx.strokeStyle = '#333';
  ctx.lineWidth = scale;
  ctx.strokeRect(b.x, b.y, b.w, b.h);
  ctx.fillStyle = '#333';
  ctx.font = `${FONT * scale}px system-ui, sans-serif`;
  ctx.textAlign = 'left';
  ctx.textBaseline = 'middle';
  for (const v of ticks(0, max, 4)) {
    const py = b.y + b.h - (v / max) * b.h;
    ctx.beginPath();
    ctx.moveTo(b.x + b.w, py);
    ctx.lineTo(b.x + b.w + 3 * scale, py);
    ctx.stroke();
    ctx.fillText(fmt(v), b.x + b.w + 5 * scale, py);
  }
  ctx.textAlign = 'center';
  ctx.textBaseline = 'bottom';
  ctx.fillText(title, b.x + b.w / 2, b.y - 4 * scale);
  ctx.restore();
}

/** Plot box, colour-bar box and scale of a canvas of the given device size. */
function layout(canvas, bar = true) {
  const scale = window.devicePixelRatio || 1;
  const s = scale * (document.body.classList.contains('present') ? 1.4 : 1);
  const left = 48 * s;
  const bottom = (FONT * 2 + 14) * s;
  const top = (FONT + 10) * s;
  const right = bar ? 70 * s : 10 * s;
  const plot = { x: left, y: top, w: Math.max(10, canvas.width - left - right), h: Math.max(10, canvas.height - top - bottom) };
  const barBox = { x: plot.x + plot.w + 14 * s, y: plot.y, w: 12 * s, h: plot.h };
  return { plot, bar: barBox, scale: s };
}

/**
 * The heat strip: column by column, each time's density relative to its maximum, kept in an
 * off-screen canvas of the plot box so that a frame draws only its new columns; `compose`
 * puts it on screen with axes, colour bar, the truth and the time cursor.
 */
export class HeatStrip {
  constructor(canvas) {
    this.canvas = canvas;
    this.off = new OffscreenCanvas(1, 1);
    this.range = { t0: 0, t1: 1, lo: 0, hi: 1, label: 'x' };
    this.x = 0;
  }

  /** A new run or component: clears the columns. */
  reset(range) {
    this.range = range;
    this.clear();
  }

  /** Fits the canvas to its panel's width and `cssHeight` (clears the columns). */
  fit(cssHeight) {
    const width = this.canvas.parentElement.clientWidth - 8;
    sizeCanvas(this.canvas, Math.max(200, width), cssHeight);
    this.box = layout(this.canvas);
    this.clear();
  }

  clear() {
    this.off = new OffscreenCanvas(Math.max(1, Math.round(this.box.plot.w)), Math.max(1, Math.round(this.box.plot.h)));
    this.x = 0;
  }

  /** Columns from the last drawn one up to time `t`, coloured by `density` (one time's values). */
  column(t, density) {
    const { t0, t1 } = this.range;
    const W = this.off.width;
    const H = this.off.height;
    const x1 = Math.min(W, Math.ceil(((t - t0) / (t1 - t0)) * W));
    if (!density?.length || x1 <= this.x) return;
    let max = 0;
    for (const v of density) if (v > max) max = v;
    const ctx = this.off.getContext('2d');
    const img = ctx.createImageData(x1 - this.x, H);
    for (let y = 0; y < H; y++) {
      const gi = Math.min(density.length - 1, Math.floor(((H - 1 - y) / Math.max(1, H - 1)) * (density.length - 1) + 0.5));
      const c = colormap(max > 0 ? density[gi] / max : 0);
      for (let x = 0; x < x1 - this.x; x++) {
        const o = 4 * (y * (x1 - this.x) + x);
        img.data[o] = c[0]; img.data[o + 1] = c[1]; img.data[o + 2] = c[2]; img.data[o + 3] = 255;
      }
    }
    ctx.putImageData(img, this.x, 0);
    this.x = x1;
  }

  /** Draws the strip with axes, colour bar, the truth (`times`, `values`) and a cursor. */
  compose({ times = [], truth = null, cursor = null } = {}) {
    const ctx = this.canvas.getContext('2d');
    const { plot: b, bar, scale } = this.box;
    const { t0, t1, lo, hi, label } = this.range;
    ctx.fillStyle = '#fff';
    ctx.fillRect(0, 0, this.canvas.width, this.canvas.height);
    ctx.fillStyle = '#eee';
    ctx.fillRect(b.x, b.y, b.w, b.h);
    ctx.imageSmoothingEnabled = false;
    ctx.drawImage(this.off, b.x, b.y, b.w, b.h);
    if (truth) {
      ctx.fillStyle = '#fff';
      const r = 1.2 * scale;
      for (let i = 0; i < times.length; i++) {
        const v = truth[i];
        if (v == null || v < lo || v > hi) continue;
        ctx.fillRect(b.x + ((times[i] - t0) / (t1 - t0)) * b.w - r, b.y + b.h - ((v - lo) / (hi - lo)) * b.h - r, 2 * r, 2 * r);
      }
    }
    if (cursor != null) {
      const px = b.x + ((cursor - t0) / (t1 - t0)) * b.w;
      ctx.save();
      ctx.strokeStyle = '#e00';
      ctx.lineWidth = 2 * scale;
      ctx.beginPath();
      ctx.moveTo(px, b.y);
      ctx.lineTo(px, b.y + b.h);
      ctx.stroke();
      ctx.restore();
    }
    axes(ctx, b, [t0, t1], [lo, hi], 't', label, scale);
    colourBar(ctx, bar, 1, 'p / max p', scale);
  }
}

const MARKERS = ['square', 'circle', 'triangle', 'diamond'];

function marker(ctx, shape, x, y, r) {
  ctx.beginPath();
  if (shape === 'circle') ctx.arc(x, y, r, 0, 2 * Math.PI);
  else if (shape === 'triangle') { ctx.moveTo(x, y - r); ctx.lineTo(x + r, y + r); ctx.lineTo(x - r, y + r); ctx.closePath(); }
  else if (shape === 'diamond') { ctx.moveTo(x, y - r); ctx.lineTo(x + r, y); ctx.lineTo(x, y + r); ctx.lineTo(x - r, y); ctx.closePath(); }
  else ctx.rect(x - r, y - r, 2 * r, 2 * r);
}

/** The shape of method `i`'s estimate marker on the heatmap (and its key). */
export const markerShape = (i) => MARKERS[i % MARKERS.length];

/**
 * The 2-D heatmap: `values` on a `P × P` raster over `domain` (first component fastest; its
 * axes named by `labels`),
 * coloured against its maximum with a numeric colour bar, at most `height` CSS pixels high; `curvature` (optional) tints in
 * red where ∇²(−log p) is not positive semidefinite; `marks` are estimates `{x, y, color, i}`
 * (thin hollow markers growing with the method's index, so coinciding ones stay visible) and
 * `truth` a white disc drawn over them.
 */
export function drawHeatmap2d(canvas, { height, values, P, domain, labels = ['x1', 'x2'], curvature = null, marks = [], truth = null }) {
  // The plot box square: the canvas is a little wider than high (colour bar on the right).
  const width = Math.max(260, Math.min(canvas.parentElement.clientWidth - 8, height * 1.16));
  sizeCanvas(canvas, width, width / 1.16);
  const { plot: b, bar, scale } = layout(canvas);
  const ctx = canvas.getContext('2d');
  ctx.fillStyle = '#fff';
  ctx.fillRect(0, 0, canvas.width, canvas.height);
  const [[x0, x1], [y0, y1]] = domain;
  let max = 0;
  if (values?.length) {
    for (const v of values) if (v > max) max = v;
    const img = new ImageData(P, P);
    for (let j = 0; j < P; j++) {
      for (let i = 0; i < P; i++) {
        // Row j of the raster is y = ys[j]; the canvas has y growing upwards.
        const v = values[i + P * j];
        let c = colormap(max > 0 ? v / max : 0);
        const k = curvature ? curvature[i + P * j] : NaN;
        if (k < -1e-6) c = [Math.round(0.45 * c[0] + 0.55 * 230), Math.round(0.45 * c[1] + 0.55 * 30), Math.round(0.45 * c[2] + 0.55 * 40)];
        const o = 4 * (i + P * (P - 1 - j));
        img.data[o] = c[0]; img.data[o + 1] = c[1]; img.data[o + 2] = c[2]; img.data[o + 3] = 255;
      }
    }
    const off = new OffscreenCanvas(P, P);
    off.getContext('2d').putImageData(img, 0, 0);
    ctx.imageSmoothingEnabled = false;
    ctx.drawImage(off, b.x, b.y, b.w, b.h);
  } else {
    ctx.fillStyle = '#eee';
    ctx.fillRect(b.x, b.y, b.w, b.h);
  }
  const px = (x) => b.x + ((x - x0) / (x1 - x0)) * b.w;
  const py = (y) => b.y + b.h - ((y - y0) / (y1 - y0)) * b.h;
  ctx.save();
  ctx.beginPath();
  ctx.rect(b.x, b.y, b.w, b.h);
  ctx.clip();
  // Thin hollow markers, small beside a posterior a few cells wide, and the truth on top.
  for (const m of marks) {
    const r = (4 + 1.5 * m.i) * scale;
    ctx.lineWidth = 2.4 * scale;
    ctx.strokeStyle = '#000';
    marker(ctx, markerShape(m.i), px(m.x), py(m.y), r);
    ctx.stroke();
    ctx.lineWidth = 1.3 * scale;
    ctx.strokeStyle = m.color;
    ctx.stroke();
  }
  if (truth) {
    ctx.beginPath();
    ctx.arc(px(truth[0]), py(truth[1]), 4 * scale, 0, 2 * Math.PI);
    ctx.fillStyle = '#fff';
    ctx.fill();
    ctx.strokeStyle = '#000';
    ctx.lineWidth = scale;
    ctx.stroke();
  }
  ctx.restore();
  axes(ctx, b, [x0, x1], [y0, y1], labels[0], labels[1], scale);
  colourBar(ctx, bar, max > 0 ? max : 1, 'density', scale);
}
