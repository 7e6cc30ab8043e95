// The web view's page: reads the run's JSON frames (src/symb/apps/view/view_json.hpp says what
// each holds) from /ws and sends one-line commands back (live_view.hpp lists them). Plain
// JavaScript, no build step, nothing fetched from elsewhere: it works offline. The world is 2D
// (drawn here), 3D (organism.js) or none (a board: the world is the simulator's); plots over
// time are plots.js's.
'use strict';

const $ = (id) => document.getElementById(id);
const token = new URLSearchParams(location.search).get('token') || '';
const ws = new WebSocket(`ws://${location.host}/ws?token=${encodeURIComponent(token)}`);
const canvas = $('world');
const ctx = canvas.getContext('2d');
const kMaxTrail = 2000;          // points per robot
const kMaxTrailRobots = 200;     // bigger swarms: no trails, dots only
const palette = ['#1f77b4', '#ff7f0e', '#2ca02c', '#d62728', '#9467bd', '#8c564b', '#e377c2', '#7f7f7f'];

const view = { world: null, kind: 'none', robots: [], selected: 0, poses: null, stride: 1, trails: [], paused: false,
               virtual: true, organism: Organism.state(), probes: new Map(), spikes: new Map(), fitness: new Map() };
let opened = false;

function send(line) { if (ws.readyState === WebSocket.OPEN) ws.send(line); }
function setConn(text, cls) { const c = $('conn'); c.textContent = text; c.className = 'state ' + (cls || ''); }

ws.onopen = () => { opened = true; setConn('live', 'live'); };
ws.onclose = () => {
  // A refused token never opens: the server answers the upgrade with an error.
  if (!opened) setConn('refused: wrong token or too many viewers', 'refused');
  else if (!$('conn').textContent.startsWith('run finished')) setConn('closed', 'closed');
};
ws.onmessage = (ev) => {
  const m = JSON.parse(ev.data);
  const handler = handlers[m.type];
  if (handler) handler(m);
};

const handlers = {
  hello(m) {
    view.world = m.world;
    view.kind = !m.world ? 'none' : m.world.kind === 'organism' ? '3d' : '2d';
    document.body.dataset.world = view.kind;
    if (view.kind === '3d') Organism.hello(view.organism, m.world);
    canvas.dataset.modules = view.kind === '3d' ? m.world.modules.length : 0;
    view.robots = m.robots;
    view.selected = m.selected;
    view.virtual = m.virtual;
    view.trails = m.robots.map(() => []);
    $('scenario').textContent = m.scenario;
    const sel = $('robot');
    sel.innerHTML = '';
    m.robots.forEach((name, i) => sel.add(new Option(name, name, false, i === m.selected)));
    for (const b of document.querySelectorAll('.controls button')) b.disabled = !m.virtual;
    showStatus(m);
    fitCanvas();
    requestDraw();
  },
  step(m) {
    view.poses = m.xy;
    view.stride = m.stride;
    $('clock').textContent = `t = ${m.t.toFixed(1)} s`;
    const count = m.xy.length / 3;
    if (count <= kMaxTrailRobots) {
      for (let k = 0; k < count; ++k) {
        const trail = view.trails[k * m.stride] || (view.trails[k * m.stride] = []);
        trail.push(m.xy[3 * k], m.xy[3 * k + 1]);
        if (trail.length > 2 * kMaxTrail) trail.splice(0, trail.length - 2 * kMaxTrail);
      }
    }
    const k = view.selected / m.stride;
    if (Number.isInteger(k) && 3 * k + 2 < m.xy.length)
      $('robot-pos').textContent = `x ${m.xy[3 * k].toFixed(1)} y ${m.xy[3 * k + 1].toFixed(1)} cm, ${m.xy[3 * k + 2]}°`;
    requestDraw();
  },
  organism(m) {
    const o = view.organism;
    Organism.frame(o, m);
    $('clock').textContent = `t = ${m.t.toFixed(1)} s`;
    const p = o.poses[view.selected];
    if (p) $('robot-pos').textContent =
      `x ${(100 * p.p[0]).toFixed(1)} y ${(100 * p.p[1]).toFixed(1)} z ${(100 * p.p[2]).toFixed(1)} cm, ` +
      `hinge ${(p.hinge * 180 / Math.PI).toFixed(0)}\u00b0`;
    const links = Organism.topology(o);
    $('topology').textContent = links.length ? `docked: ${links.join(', ')}` : 'docked: none';
    $('topology').dataset.pairs = links.length;
    requestDraw();
  },
  graph(m) {
    for (const e of document.querySelectorAll('.robot-name')) e.textContent = m.robot;
    const tasks = $('tasks').tBodies[0];
    tasks.innerHTML = '';
    for (const t of m.tasks) {
      const row = tasks.insertRow();
      row.className = t.state;
      row.dataset.task = t.name;
      for (const v of [t.name, t.type, t.state, t.priority, t.period > 0 ? `${(t.period * 1000).toFixed(1)} ms` : '-',
                       `${t.queue}/${t.capacity}`, t.in, t.out, t.dropped])
        row.insertCell().textContent = v;
    }
    const hooks = $('hooks').tBodies[0];
    hooks.innerHTML = '';
    for (const h of m.hooks) {
      const row = hooks.insertRow();
      row.className = h.enabled ? 'enabled' : 'disabled';
      row.dataset.hook = `${h.sender}->${h.receiver}`;
      for (const v of [h.hook, h.sender, h.receiver, h.priority, h.policy,
                       h.suppress > 0 ? `${(h.suppress * 1000).toFixed(0)} ms` : '-',
                       h.inhibited ? 'inhibited' : (h.enabled ? 'enabled' : 'disabled'),
                       h.sent, h.delivered, h.dropped, h.suppressed, h.queued])
        row.insertCell().textContent = v;
    }
  },
  log(m) {
    const log = $('log');
    const follow = log.scrollTop + log.clientHeight >= log.scrollHeight - 4;
    log.textContent += m.lines.join('\n') + '\n';
    if (log.textContent.length > 100000) log.textContent = log.textContent.slice(-50000);
    if (follow) log.scrollTop = log.scrollHeight;
  },
  probes(m) {
    const box = $('probes');
    if (m.full) { view.probes.clear(); box.innerHTML = ''; }
    for (const p of m.probes) {
      const key = `${p.task}/${p.channel}`;
      let e = view.probes.get(key);
      if (!e) {
        const row = document.createElement('div');
        row.className = 'probe';
        row.dataset.probe = key;
        const label = document.createElement('span');
        label.className = 'label';
        label.textContent = key;
        label.title = key;
        const plot = document.createElement('canvas');
        plot.className = 'plot';
        plot.width = 180;
        plot.height = 32;
        const bars = document.createElement('span');
        bars.className = 'bars';
        const values = document.createElement('span');
        values.className = 'values';
        row.append(label, plot, bars, values);
        box.append(row);
        e = { row, plot, bars, values, series: Plots.series(p.width) };
        view.probes.set(key, e);
      }
      Plots.append(e.series, p.points);
      e.row.dataset.points = e.series.t.length;
      Plots.drawSeries(e.plot, [e.series]);
      const top = Math.max(1e-9, ...p.values.map((v) => Math.abs(v ?? 0)));
      e.bars.innerHTML = '';
      for (const v of p.values.slice(0, 32)) {
        const bar = document.createElement('span');
        bar.style.height = `${Math.round(28 * Math.abs(v ?? 0) / top)}px`;
        e.bars.append(bar);
      }
      e.values.textContent = p.values.map((v) => (v === null ? 'NaN' : v.toPrecision(3))).join(' ');
    }
  },
  spikes(m) {
    $('spikes-pane').hidden = false;
    let e = view.spikes.get(m.task);
    if (!e) {
      const row = document.createElement('div');
      row.className = 'raster';
      row.dataset.task = m.task;
      const label = document.createElement('div');
      const plot = document.createElement('canvas');
      plot.width = 360;
      plot.height = 90;
      row.append(label, plot);
      $('spikes').append(row);
      e = { row, label, plot, raster: Plots.raster() };
      view.spikes.set(m.task, e);
    }
    Plots.addSpikes(e.raster, m.dots);
    e.row.dataset.spikes = e.raster.total;
    e.label.textContent = `${m.task}: ${e.raster.total} spikes, the last 5 s` + (m.dropped ? ` (${m.dropped} not shown)` : '');
    Plots.drawRaster(e.plot, e.raster);
  },
  fitness(m) {
    $('fitness-pane').hidden = false;
    if (m.full) view.fitness.clear();
    for (const s of m.series) {
      if (!view.fitness.has(s.channel)) view.fitness.set(s.channel, Plots.series(s.width));
      Plots.append(view.fitness.get(s.channel), s.points);
    }
    const names = [...view.fitness.keys()];
    const list = names.map((n) => view.fitness.get(n));
    const points = list.reduce((a, s) => a + s.t.length, 0);
    const plot = $('fitness');
    plot.dataset.points = points;
    // Each evaluation's fitness as dots, the champion's (best, mean) as lines.
    Plots.drawSeries(plot, list, { axes: true, pad: 16, dots: (j) => names[j] === 'fitness' });
    $('fitness-legend').innerHTML = '';
    names.forEach((n, j) => {
      const item = document.createElement('span');
      item.style.color = Plots.colours[j % Plots.colours.length];
      item.textContent = `${n} (${view.fitness.get(n).t.length}) `;
      $('fitness-legend').append(item);
    });
    $('fitness-title').textContent = `Fitness of ${m.robot} (${m.task})`;
  },
  status(m) {
    showStatus(m);
    if (view.kind === 'none') $('clock').textContent = `t = ${m.t.toFixed(1)} s`;  // no world frames to tell
    if (m.finished) setConn('run finished', 'closed');
  },
  shell(m) {
    const out = $('shell-output');
    out.textContent += m.text;
    out.scrollTop = out.scrollHeight;
  },
};

function showStatus(m) {
  view.paused = m.paused;
  $('pause').textContent = m.paused ? 'resume' : 'pause';
  $('speed').textContent = !m.virtual ? 'wall clock' : m.speed > 0 ? `x${m.speed}` : 'as fast as possible';
  $('speed').dataset.speed = m.speed;
  document.body.dataset.paused = m.paused;
  if (m.dropped !== undefined) $('dropped').textContent = m.dropped ? `${m.dropped} frames dropped` : '';
}

function fitCanvas() {
  if (view.kind === '2d') {
    canvas.width = 800;
    canvas.height = Math.round(800 * view.world.height / view.world.width);
  } else if (view.kind === '3d') {
    canvas.width = 800;
    canvas.height = 560;
  }
}

// The world is drawn at most once per animation frame, not at every frame from the run: frames
// that arrive together cost one drawing, and a page in a background tab (no animation frames)
// draws nothing until it is shown again.
let drawRequested = false;
function requestDraw() {
  if (drawRequested) return;
  drawRequested = true;
  requestAnimationFrame(() => {
    drawRequested = false;
    draw();
  });
}

function draw() {
  if (view.kind === '3d') return Organism.draw(view.organism, canvas, ctx, view.selected, palette);
  const w = view.world;
  if (!w) return;
  const s = canvas.width / w.width;
  const X = (x) => x * s;
  const Y = (y) => canvas.height - y * s;   // the world's y points up
  ctx.clearRect(0, 0, canvas.width, canvas.height);
  for (const z of w.zones) {
    const g = Math.round(255 * Math.min(1, Math.max(0, z.ground)));
    ctx.fillStyle = `rgb(${g},${g},${g})`;
    if (z.r !== undefined) { ctx.beginPath(); ctx.arc(X(z.cx), Y(z.cy), z.r * s, 0, 2 * Math.PI); ctx.fill(); }
    else ctx.fillRect(X(z.x1), Y(z.y2), (z.x2 - z.x1) * s, (z.y2 - z.y1) * s);
  }
  ctx.strokeStyle = '#333';
  ctx.lineWidth = 2;
  ctx.strokeRect(1, 1, canvas.width - 2, canvas.height - 2);
  for (const [x1, y1, x2, y2, thick] of w.walls) {
    ctx.lineWidth = Math.max(1, thick * s);
    ctx.beginPath(); ctx.moveTo(X(x1), Y(y1)); ctx.lineTo(X(x2), Y(y2)); ctx.stroke();
  }
  ctx.lineWidth = 2;
  view.trails.forEach((t, i) => {
    if (!t || t.length < 4) return;
    ctx.strokeStyle = palette[i % palette.length];
    ctx.globalAlpha = 0.6;
    ctx.beginPath(); ctx.moveTo(X(t[0]), Y(t[1]));
    for (let k = 2; k < t.length; k += 2) ctx.lineTo(X(t[k]), Y(t[k + 1]));
    ctx.stroke();
    ctx.globalAlpha = 1;
  });
  ctx.lineWidth = 1;
  const p = view.poses;
  if (!p) return;
  const count = p.length / 3;
  const r = count > kMaxTrailRobots ? Math.max(1.5, 2 * s) : 5.5 * s;   // a Thymio is 11 cm across
  for (let k = 0; k < count; ++k) {
    const i = k * view.stride;
    const x = X(p[3 * k]), y = Y(p[3 * k + 1]), a = p[3 * k + 2] * Math.PI / 180;
    ctx.fillStyle = palette[i % palette.length];
    ctx.beginPath(); ctx.arc(x, y, r, 0, 2 * Math.PI); ctx.fill();
    if (i === view.selected) {   // the chosen robot: a ring around it
      ctx.strokeStyle = '#000';
      ctx.lineWidth = 2;
      ctx.beginPath(); ctx.arc(x, y, r + 3, 0, 2 * Math.PI); ctx.stroke();
      ctx.lineWidth = 1;
    }
    if (count <= kMaxTrailRobots) {
      ctx.strokeStyle = '#000';
      ctx.beginPath(); ctx.moveTo(x, y); ctx.lineTo(x + r * Math.cos(a), y - r * Math.sin(a)); ctx.stroke();
    }
  }
}

function choose(name) {
  view.selected = view.robots.indexOf(name);
  $('robot').value = name;
  $('log').textContent = '';
  view.probes.clear();
  $('probes').innerHTML = '';
  view.spikes.clear();
  $('spikes').innerHTML = '';
  $('spikes-pane').hidden = true;
  send(`robot ${name}`);
  draw();
}
$('robot').onchange = (e) => choose(e.target.value);
// A click on the world chooses the robot nearest to it; in 3D a drag turns the camera and the
// wheel zooms.
let drag = null;
canvas.onmousedown = (e) => { drag = { x: e.clientX, y: e.clientY, moved: false }; };
window.addEventListener('mouseup', () => { setTimeout(() => { drag = null; }, 0); });
canvas.onmousemove = (e) => {
  if (!drag || view.kind !== '3d') return;
  const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
  if (Math.abs(dx) + Math.abs(dy) > 2) drag.moved = true;
  Organism.orbit(dx, dy);
  drag.x = e.clientX;
  drag.y = e.clientY;
  draw();
};
canvas.addEventListener('wheel', (e) => {
  if (view.kind !== '3d') return;
  e.preventDefault();
  Organism.zoom(e.deltaY > 0 ? 1.1 : 1 / 1.1);
  draw();
}, { passive: false });
canvas.onclick = (e) => {
  if (drag && drag.moved) return;
  const rect = canvas.getBoundingClientRect();
  const cx = (e.clientX - rect.left) * canvas.width / rect.width;
  const cy = (e.clientY - rect.top) * canvas.height / rect.height;
  if (view.kind === '3d') {
    const best = Organism.pick(view.organism, canvas, cx, cy);
    if (best >= 0) choose(view.robots[best]);
    return;
  }
  const p = view.poses;
  if (!p || !view.world) return;
  const s = canvas.width / view.world.width;
  const x = cx / s;
  const y = (canvas.height - cy) / s;
  let best = -1, bestD = Infinity;
  for (let k = 0; k < p.length / 3; ++k) {
    const d = (p[3 * k] - x) ** 2 + (p[3 * k + 1] - y) ** 2;
    if (d < bestD) { bestD = d; best = k * view.stride; }
  }
  if (best >= 0) choose(view.robots[best]);
};
$('pause').onclick = () => send(view.paused ? 'resume' : 'pause');
$('step').onclick = () => send('step');
for (const b of document.querySelectorAll('button.speed')) b.onclick = () => send(`speed ${b.dataset.speed}`);
$('shell-form').onsubmit = (e) => {
  e.preventDefault();
  const input = $('shell-input');
  $('shell-output').textContent += `> ${input.value}\n`;
  send(`shell ${input.value}`);
  input.value = '';
};
