// The web view's plots over time, on plain canvases: a probe series' values (one line per value,
// up to its width), a spiking network's raster (a dot per spike, time across, neuron up), and an
// evolution's fitness (each evaluation a dot, the champion's a line). The history they draw is
// kept here, bounded: at most kMaxPoints points a series (every other one goes when full), the
// raster's last kRasterSeconds.
'use strict';

const Plots = (() => {
  const kMaxPoints = 1024;
  const kRasterSeconds = 5;
  const kMaxDots = 20000;
  const colours = ['#1f77b4', '#ff7f0e', '#2ca02c', '#d62728', '#9467bd', '#8c564b', '#e377c2', '#7f7f7f'];

  // A series: times and, per value, its numbers. `points` is flat: time, then `width` values.
  function series(width) { return { width, t: [], v: Array.from({ length: width }, () => []) }; }
  function append(s, points) {
    const row = s.width + 1;
    for (let k = 0; k + row <= points.length; k += row) {
      s.t.push(points[k]);
      for (let i = 0; i < s.width; ++i) s.v[i].push(points[k + 1 + i]);
    }
    if (s.t.length > kMaxPoints) {
      const keep = (a) => a.filter((_, i) => i % 2 === 0);
      s.t = keep(s.t);
      s.v = s.v.map(keep);
    }
  }

  function range(values) {
    let lo = Infinity, hi = -Infinity;
    for (const a of values) for (const x of a) if (x !== null && Number.isFinite(x)) { lo = Math.min(lo, x); hi = Math.max(hi, x); }
    if (lo === Infinity) return [0, 1];
    if (hi - lo < 1e-9) { lo -= 0.5; hi += 0.5; }
    return [lo, hi];
  }

  // Lines of a series over its whole time span; `dots`: value 0 as dots instead (fitness).
  function drawSeries(canvas, list, opts = {}) {
    const ctx = canvas.getContext('2d');
    const W = canvas.width, H = canvas.height, pad = opts.pad ?? 2;
    ctx.clearRect(0, 0, W, H);
    let t0 = Infinity, t1 = -Infinity;
    for (const s of list) if (s.t.length) { t0 = Math.min(t0, s.t[0]); t1 = Math.max(t1, s.t[s.t.length - 1]); }
    if (t0 === Infinity) return;
    if (t1 - t0 < 1e-9) t1 = t0 + 1;
    const [lo, hi] = range(list.flatMap((s) => s.v));
    const X = (t) => pad + (W - 2 * pad) * (t - t0) / (t1 - t0);
    const Y = (v) => H - pad - (H - 2 * pad) * (v - lo) / (hi - lo);
    if (opts.axes) {
      ctx.fillStyle = '#666';
      ctx.font = '11px system-ui, sans-serif';
      ctx.fillText(hi.toPrecision(3), 2, 11);
      ctx.fillText(lo.toPrecision(3), 2, H - 3);
      ctx.fillText(`${t0.toFixed(0)} s`, pad, H - 14);
      ctx.fillText(`${t1.toFixed(0)} s`, W - 40, H - 14);
    }
    list.forEach((s, j) => {
      s.v.forEach((vals, i) => {
        ctx.strokeStyle = ctx.fillStyle = colours[(j + i) % colours.length];
        if (opts.dots && opts.dots(j)) {
          for (let k = 0; k < vals.length; ++k)
            if (vals[k] !== null) ctx.fillRect(X(s.t[k]) - 1, Y(vals[k]) - 1, 2.5, 2.5);
          return;
        }
        ctx.beginPath();
        let on = false;
        for (let k = 0; k < vals.length; ++k) {
          if (vals[k] === null) { on = false; continue; }
          if (on) ctx.lineTo(X(s.t[k]), Y(vals[k])); else { ctx.moveTo(X(s.t[k]), Y(vals[k])); on = true; }
        }
        ctx.stroke();
      });
    });
  }

  // A raster: dots is flat (time s, neuron) pairs; kept to the last kRasterSeconds.
  function raster() { return { t: [], n: [], maxNeuron: 1, total: 0 }; }
  function addSpikes(r, dots) {
    for (let k = 0; k + 1 < dots.length; k += 2) {
      r.t.push(dots[k]);
      r.n.push(dots[k + 1]);
      r.maxNeuron = Math.max(r.maxNeuron, dots[k + 1]);
      ++r.total;
    }
    const last = r.t.length ? r.t[r.t.length - 1] : 0;
    let cut = 0;
    while (cut < r.t.length && (r.t[cut] < last - kRasterSeconds || r.t.length - cut > kMaxDots)) ++cut;
    if (cut) { r.t.splice(0, cut); r.n.splice(0, cut); }
  }
  function drawRaster(canvas, r) {
    const ctx = canvas.getContext('2d');
    const W = canvas.width, H = canvas.height;
    ctx.clearRect(0, 0, W, H);
    if (!r.t.length) return;
    const t1 = r.t[r.t.length - 1], t0 = t1 - kRasterSeconds;
    ctx.fillStyle = '#222';
    for (let k = 0; k < r.t.length; ++k)
      ctx.fillRect(W * (r.t[k] - t0) / kRasterSeconds, H - 1 - (H - 2) * r.n[k] / r.maxNeuron, 1.5, 1.5);
  }

  return { series, append, drawSeries, raster, addSpikes, drawRaster, colours };
})();
