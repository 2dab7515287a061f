/* Globals: el, svgEl, fmt, barChart, horizontalBars, heatmap, frameSvg, pairSvg. */
// Small plotting helpers: DOM and SVG builders, bar charts, heatmaps and image overlays.
'use strict';
const SVG_NS = 'http://www.w3.org/2000/svg';
const PALETTE = { blue: '#2f6fdf', orange: '#e8833a', green: '#2e9d62', red: '#d2423b',
                  grey: '#a9b1bf', purple: '#7b5cd6' };

function el(tag, attrs, parent, text) {
  const node = document.createElement(tag);
  for (const [key, value] of Object.entries(attrs || {})) node.setAttribute(key, value);
  if (text !== undefined) node.textContent = text;
  if (parent) parent.appendChild(node);
  return node;
}

function svgEl(tag, attrs, parent, text) {
  const node = document.createElementNS(SVG_NS, tag);
  for (const [key, value] of Object.entries(attrs || {})) node.setAttribute(key, value);
  if (text !== undefined) node.textContent = text;
  if (parent) parent.appendChild(node);
  return node;
}

// Formats a number for labels: integers with thousands separators, others with 3 digits.
function fmt(value, digits) {
  if (value === null || value === undefined || Number.isNaN(value)) return '–';
  if (digits !== undefined) return Number(value).toFixed(digits);
  if (Number.isInteger(value)) return value.toLocaleString('en-US');
  const magnitude = Math.abs(value);
  if (magnitude >= 100) return value.toFixed(0);
  if (magnitude >= 10) return value.toFixed(1);
  if (magnitude >= 1) return value.toFixed(2);
  return value.toPrecision(3);
}

// Shows `data-tip` of the element under the mouse in the shared tooltip.
function installTooltips() {
  const tip = document.getElementById('tooltip');
  document.addEventListener('mousemove', (event) => {
    const target = event.target.closest ? event.target.closest('[data-tip]') : null;
    if (!target) { tip.style.display = 'none'; return; }
    tip.textContent = target.getAttribute('data-tip');
    tip.style.display = 'block';
    tip.style.left = Math.min(event.clientX + 14, window.innerWidth - tip.offsetWidth - 8) + 'px';
    tip.style.top = (event.clientY + 14) + 'px';
  });
}

// About `count` round tick values covering [0, max].
function niceTicks(max, count) {
  if (!(max > 0)) return [0, 1];
  const raw = max / count;
  const power = Math.pow(10, Math.floor(Math.log10(raw)));
  const step = [1, 2, 2.5, 5, 10].map((m) => m * power).find((s) => s >= raw);
  const ticks = [];
  for (let value = 0; value <= max + step * 0.999; value += step) ticks.push(+value.toPrecision(12));
  return ticks;
}

function legend(parent, series) {
  const box = el('div', { class: 'legend' }, parent);
  for (const s of series) el('span', { style: '--swatch:' + s.color }, box, s.name);
}

// Tick labels: at most 4 significant digits, no trailing zeros.
function fmtTick(value) {
  return Math.abs(value) >= 1000 ? fmt(Math.round(value)) : String(+value.toPrecision(4));
}

// A label for an image: file name without folder and extension, shortened in the middle.
function shortName(name) {
  const base = name.split('/').pop().replace(/\.[A-Za-z0-9]{2,5}$/, '');
  return base.length > 16 ? base.slice(0, 7) + '…' + base.slice(-7) : base;
}

// Vertical grouped bar chart. spec: {labels, series: [{name, values, color, colors?}],
// yTitle, xTitle, width, height, tips: index -> text, digits}.
function barChart(parent, spec) {
  const width = spec.width || 1260, height = spec.height || 300;
  const n = spec.labels.length;
  const shortLabels = spec.shortLabels || spec.labels.map(shortName);
  const longest = Math.max(1, ...shortLabels.map((label) => label.length));
  // Labels turn when they would not fit side by side (about 6 units per character).
  const rotate = (width - 80) / Math.max(n, 1) < 6 * longest + 8;
  const margin = { left: 64, right: 16, top: 14, bottom: rotate ? 84 : 44 };
  const plotW = width - margin.left - margin.right, plotH = height - margin.top - margin.bottom;
  let max = 0;
  for (const s of spec.series) for (const v of s.values) if (v > max) max = v;
  const ticks = niceTicks(max, 5);
  const top = ticks[ticks.length - 1] || 1;
  const svg = svgEl('svg', { class: 'chart', viewBox: `0 0 ${width} ${height}` }, parent);
  const plot = svgEl('g', { transform: `translate(${margin.left},${margin.top})` }, svg);
  for (const tick of ticks) {
    const y = plotH - (tick / top) * plotH;
    svgEl('line', { x1: 0, x2: plotW, y1: y, y2: y, stroke: tick === 0 ? '#9aa3b2' : '#e6e9ef' }, plot);
    svgEl('text', { x: -8, y: y + 4, 'text-anchor': 'end' }, plot, fmtTick(tick));
  }
  const group = plotW / Math.max(n, 1);
  const inner = group * (n > 60 ? 0.9 : 0.78);
  const barW = inner / spec.series.length;
  // Rotated labels need about 13 units of spacing.
  const labelEvery = Math.max(1, Math.ceil(13 / group));
  for (let i = 0; i < n; ++i) {
    const x0 = i * group + (group - inner) / 2;
    spec.series.forEach((s, k) => {
      const v = s.values[i];
      if (v === null || v === undefined || Number.isNaN(v)) return;
      const h = (v / top) * plotH;
      const tip = spec.labels[i] + '\n' + s.name + ': ' + fmt(v, spec.digits) +
                  (spec.tips ? '\n' + spec.tips(i) : '');
      svgEl('rect', { x: x0 + k * barW, y: plotH - h, width: Math.max(barW - 0.6, 0.6),
                      height: Math.max(h, 0), fill: s.colors ? s.colors[i] : s.color,
                      rx: Math.min(2, barW / 4), 'data-tip': tip }, plot);
    });
    if (i % labelEvery === 0) {
      const lx = i * group + group / 2, ly = plotH + 14;
      const attrs = rotate ? { x: lx, y: ly, 'text-anchor': 'end',
                               transform: `rotate(-55 ${lx} ${ly})` }
                           : { x: lx, y: ly, 'text-anchor': 'middle' };
      svgEl('text', attrs, plot, shortLabels[i]);
    }
  }
  if (spec.yTitle) {
    svgEl('text', { class: 'axis-title', transform: `translate(14,${margin.top + plotH / 2}) rotate(-90)`,
                    'text-anchor': 'middle' }, svg, spec.yTitle);
  }
  if (spec.xTitle) {
    svgEl('text', { class: 'axis-title', x: margin.left + plotW / 2, y: height - 4,
                    'text-anchor': 'middle' }, svg, spec.xTitle);
  }
  if (spec.series.length > 1 || spec.legend) legend(parent, spec.series);
  return svg;
}

// Horizontal bars with value labels. spec: {labels, values, color, unit, width, digits}.
function horizontalBars(parent, spec) {
  const rowH = 30, width = spec.width || 1260;
  const margin = { left: 150, right: 150, top: 6, bottom: 6 };
  const height = margin.top + margin.bottom + rowH * spec.labels.length;
  const plotW = width - margin.left - margin.right;
  const max = Math.max(...spec.values, 1e-12);
  const total = spec.total || 0;
  const svg = svgEl('svg', { class: 'chart', viewBox: `0 0 ${width} ${height}` }, parent);
  spec.labels.forEach((label, i) => {
    const y = margin.top + i * rowH;
    const w = (spec.values[i] / max) * plotW;
    svgEl('text', { x: margin.left - 10, y: y + rowH / 2 + 4, 'text-anchor': 'end',
                    style: 'font-size:13px' }, svg, label);
    svgEl('rect', { x: margin.left, y: y + 5, width: Math.max(w, 1), height: rowH - 10, rx: 3,
                    fill: (spec.colors && spec.colors[i]) || spec.color || PALETTE.blue,
                    'data-tip': label + ': ' + fmt(spec.values[i], spec.digits) + ' ' + spec.unit },
           svg);
    let text = fmt(spec.values[i], spec.digits) + ' ' + spec.unit;
    if (total > 0) text += '  (' + (100 * spec.values[i] / total).toFixed(1) + ' %)';
    svgEl('text', { x: margin.left + w + 8, y: y + rowH / 2 + 4, style: 'font-size:12.5px' }, svg, text);
  });
  return svg;
}

// A perceptual colour ramp (close to viridis) for t in [0, 1].
function rampColor(t) {
  const stops = [[68, 1, 84], [59, 82, 139], [33, 145, 140], [94, 201, 98], [253, 231, 37]];
  t = Math.min(Math.max(t, 0), 1) * (stops.length - 1);
  const i = Math.min(Math.floor(t), stops.length - 2), f = t - i;
  const c = stops[i].map((a, k) => Math.round(a + f * (stops[i + 1][k] - a)));
  return `rgb(${c[0]},${c[1]},${c[2]})`;
}

// n x n matrix of counts as a canvas heatmap (square-root colour scale) with a tooltip.
function heatmap(parent, spec) {
  const n = spec.labels.length;
  const cell = Math.max(2, Math.min(24, Math.floor(560 / Math.max(n, 1))));
  const pad = 24;
  const figure = el('figure', {}, parent);
  el('h3', {}, figure, spec.title);
  const canvas = el('canvas', { width: n * cell + pad, height: n * cell + pad }, figure);
  const ctx = canvas.getContext('2d');
  let max = 0;
  for (const row of spec.matrix) for (const v of row) if (v > max) max = v;
  ctx.fillStyle = '#fff';
  ctx.fillRect(0, 0, canvas.width, canvas.height);
  ctx.fillStyle = '#5d6677';
  ctx.font = '10px sans-serif';
  const tickEvery = n <= 20 ? 1 : n <= 60 ? 5 : 10;
  for (let i = 0; i < n; i += tickEvery) {
    ctx.textAlign = 'center';
    ctx.fillText(String(i + 1), pad + i * cell + cell / 2, 12);
    ctx.textAlign = 'right';
    ctx.fillText(String(i + 1), pad - 4, pad + i * cell + cell / 2 + 3);
  }
  for (let i = 0; i < n; ++i) {
    for (let j = 0; j < n; ++j) {
      const v = spec.matrix[i][j];
      ctx.fillStyle = i === j ? '#eef0f4' : v > 0 ? rampColor(Math.sqrt(v / max)) : '#f7f8fa';
      ctx.fillRect(pad + j * cell, pad + i * cell, cell, cell);
    }
  }
  canvas.addEventListener('mousemove', (event) => {
    const rect = canvas.getBoundingClientRect();
    const j = Math.floor((event.clientX - rect.left - pad) / cell);
    const i = Math.floor((event.clientY - rect.top - pad) / cell);
    if (i >= 0 && j >= 0 && i < n && j < n) {
      canvas.setAttribute('data-tip', `${spec.labels[i]} × ${spec.labels[j]}\n${spec.unit}: ${spec.matrix[i][j]}`);
    } else {
      canvas.removeAttribute('data-tip');
    }
  });
  const bar = el('div', { class: 'legend' }, figure);
  const scale = el('canvas', { width: 160, height: 10 }, bar);
  const sctx = scale.getContext('2d');
  for (let x = 0; x < 160; ++x) { sctx.fillStyle = rampColor(x / 159); sctx.fillRect(x, 0, 1, 10); }
  el('em', {}, bar, `0 … ${fmt(max)} ${spec.unit} (square-root scale)`);
  return canvas;
}

// An image (or a grey placeholder) with keypoints drawn as circles of their scale, in an SVG
// whose coordinates are the image's pixels.
function frameSvg(parent, frame, keypoints) {
  const w = frame.width || 640, h = frame.height || 480;
  const svg = svgEl('svg', { class: 'frame', viewBox: `0 0 ${w} ${h}` }, parent);
  if (frame.url) {
    svgEl('image', { href: frame.url, x: 0, y: 0, width: w, height: h }, svg);
  } else {
    svgEl('rect', { x: 0, y: 0, width: w, height: h, fill: '#d5dae2' }, svg);
    svgEl('text', { x: w / 2, y: h / 2, 'text-anchor': 'middle', fill: '#6b7486',
                    'font-size': h / 14 }, svg, 'image not available');
  }
  if (keypoints) {
    const minRadius = 2.2 * w / 640;
    const group = svgEl('g', { fill: 'none', stroke: '#ffd23f', 'stroke-width': 1.1,
                               'vector-effect': 'non-scaling-stroke', opacity: 0.85 }, svg);
    for (let i = 0; i + 2 < keypoints.length; i += 3) {
      svgEl('circle', { cx: keypoints[i], cy: keypoints[i + 1],
                        r: Math.max(minRadius, keypoints[i + 2]),
                        'vector-effect': 'non-scaling-stroke' }, group);
    }
  }
  return svg;
}

// Two frames side by side (the second scaled to the first's height) joined by match lines.
function pairSvg(parent, frame1, frame2, lines) {
  const w1 = frame1.width || 640, h1 = frame1.height || 480;
  const w2 = frame2.width || 640, h2 = frame2.height || 480;
  const s2 = h1 / h2, gap = 0.02 * w1;
  const width = w1 + gap + w2 * s2;
  const svg = svgEl('svg', { class: 'frame', viewBox: `0 0 ${width} ${h1}` }, parent);
  const left = svgEl('g', {}, svg);
  const right = svgEl('g', { transform: `translate(${w1 + gap},0) scale(${s2})` }, svg);
  for (const [group, frame, w, h] of [[left, frame1, w1, h1], [right, frame2, w2, h2]]) {
    if (frame.url) svgEl('image', { href: frame.url, x: 0, y: 0, width: w, height: h }, group);
    else svgEl('rect', { x: 0, y: 0, width: w, height: h, fill: '#d5dae2' }, group);
  }
  const count = lines.length / 4;
  const group = svgEl('g', { 'stroke-width': 1.2, opacity: 0.85 }, svg);
  for (let i = 0; i < count; ++i) {
    const x1 = lines[4 * i], y1 = lines[4 * i + 1];
    const x2 = w1 + gap + s2 * lines[4 * i + 2], y2 = s2 * lines[4 * i + 3];
    const color = `hsl(${(i * 137.5) % 360},85%,58%)`;
    svgEl('line', { x1, y1, x2, y2, stroke: color, 'vector-effect': 'non-scaling-stroke' }, group);
    svgEl('circle', { cx: x1, cy: y1, r: 3 * w1 / 640, fill: color }, group);
    svgEl('circle', { cx: x2, cy: y2, r: 3 * w1 / 640, fill: color }, group);
  }
  return svg;
}
