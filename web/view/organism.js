// The web view's 3D world: an organism's modules (a 3D scenario, src/symb/apps/view/organism_view.hpp)
// drawn as boxes on a plain 2D canvas with a perspective camera that orbits the organism (drag to
// turn, wheel to zoom, click a module to choose it). Each module is two half boxes: the front half
// as its pose says, the tail turned by the hinge angle about the hinge axis. Docked connectors are
// joined by a red bar. Painter's algorithm: faces sorted far to near, no depth buffer, no library.
'use strict';

const Organism = (() => {
  const cam = { az: -2.3, el: 0.55, dist: 1.0, target: [0, 0, 0], focal: 1 };
  let eye = [0, 0, 0], fwd = [1, 0, 0], right = [0, 1, 0], up = [0, 0, 1];
  const light = norm([0.4, -0.3, 0.85]);
  const kMaxTrail = 1500;

  function sub(a, b) { return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]; }
  function add(a, b) { return [a[0] + b[0], a[1] + b[1], a[2] + b[2]]; }
  function dot(a, b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
  function cross(a, b) { return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]; }
  function norm(a) { const l = Math.hypot(a[0], a[1], a[2]) || 1; return [a[0] / l, a[1] / l, a[2] / l]; }
  // Rotates v by the unit quaternion q = [w, x, y, z].
  function rotate(q, v) {
    const [w, x, y, z] = q;
    const u = [x, y, z];
    const t = cross(u, v).map((c) => 2 * c);
    return add(add(v, t.map((c) => w * c)), cross(u, t));
  }
  // Rotates v by `angle` about the unit `axis` (Rodrigues).
  function turn(axis, angle, v) {
    const c = Math.cos(angle), s = Math.sin(angle), k = cross(axis, v), d = dot(axis, v) * (1 - c);
    return [v[0] * c + k[0] * s + axis[0] * d, v[1] * c + k[1] * s + axis[1] * d, v[2] * c + k[2] * s + axis[2] * d];
  }

  function setCamera(canvas) {
    const ce = Math.cos(cam.el);
    eye = add(cam.target, [cam.dist * ce * Math.cos(cam.az), cam.dist * ce * Math.sin(cam.az), cam.dist * Math.sin(cam.el)]);
    fwd = norm(sub(cam.target, eye));
    right = norm(cross(fwd, [0, 0, 1]));
    up = cross(right, fwd);
    cam.focal = 1.3 * canvas.height;
  }
  // Screen position and depth of a world point; depth <= 0 is behind the camera.
  function project(canvas, p) {
    const d = sub(p, eye);
    const z = dot(d, fwd);
    const s = cam.focal / Math.max(z, 1e-3);
    return [canvas.width / 2 + dot(d, right) * s, canvas.height / 2 - dot(d, up) * s, z];
  }

  // A module point (module frame, straight hinge) in the world, the tail's turned by the hinge.
  function worldPoint(shape, pose, p, tail = p[0] < 0) {
    const local = tail ? turn(shape.axis, pose.hinge, p) : p;
    return add(pose.p, rotate(pose.q, local));
  }

  const kBoxFaces = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]];

  function state() {
    return { shapes: [], poses: [], docked: [], trails: [], step: 0, t: 0, framed: false };
  }

  function hello(o, world) {
    o.shapes = world.modules.map((m) => ({
      name: m.name, size: m.size, axis: norm(m.hinge), wheels: m.wheels,
      connectors: m.connectors.map(([name, x, y, z]) => ({ name, p: [x, y, z] })),
    }));
    o.poses = [];
    o.trails = o.shapes.map(() => []);
    o.framed = false;
  }

  function frame(o, m) {
    o.step = m.step;
    o.t = m.t;
    o.poses = [];
    for (let k = 0; 8 * k + 7 < m.m.length; ++k) {
      const a = m.m.slice(8 * k, 8 * k + 8);
      o.poses.push({ p: [a[0], a[1], a[2]], q: [a[3], a[4], a[5], a[6]], hinge: a[7] });
      const trail = o.trails[k] || (o.trails[k] = []);
      trail.push(a[0], a[1]);
      if (trail.length > 2 * kMaxTrail) trail.splice(0, trail.length - 2 * kMaxTrail);
    }
    o.docked = m.docked;
    // The camera looks at the organism's centre (smoothly, so a moving organism stays in view).
    if (o.poses.length) {
      const c = [0, 0, 0];
      for (const p of o.poses) for (let i = 0; i < 3; ++i) c[i] += p.p[i] / o.poses.length;
      if (!o.framed) {
        cam.target = c;
        let r = 0.2;
        for (const p of o.poses) r = Math.max(r, Math.hypot(p.p[0] - c[0], p.p[1] - c[1]));
        cam.dist = 3 * r;
        o.framed = true;
      } else {
        for (let i = 0; i < 3; ++i) cam.target[i] += 0.1 * (c[i] - cam.target[i]);
      }
    }
  }

  function draw(o, canvas, ctx, selected, palette) {
    setCamera(canvas);
    ctx.clearRect(0, 0, canvas.width, canvas.height);
    // The floor: a 10 cm grid around the organism.
    ctx.strokeStyle = '#e2e2e2';
    ctx.lineWidth = 1;
    const g0x = Math.round(cam.target[0] * 10) / 10, g0y = Math.round(cam.target[1] * 10) / 10;
    const line = (a, b) => {
      const p = project(canvas, a), q = project(canvas, b);
      if (p[2] <= 0.01 || q[2] <= 0.01) return;
      ctx.beginPath(); ctx.moveTo(p[0], p[1]); ctx.lineTo(q[0], q[1]); ctx.stroke();
    };
    for (let k = -10; k <= 10; ++k) {
      line([g0x + k / 10, g0y - 1, 0], [g0x + k / 10, g0y + 1, 0]);
      line([g0x - 1, g0y + k / 10, 0], [g0x + 1, g0y + k / 10, 0]);
    }
    // Trails of the modules' centres on the floor.
    o.trails.forEach((t, i) => {
      if (!t || t.length < 4) return;
      ctx.strokeStyle = palette[i % palette.length];
      ctx.globalAlpha = 0.5;
      ctx.beginPath();
      let started = false;
      for (let k = 0; k < t.length; k += 2) {
        const p = project(canvas, [t[k], t[k + 1], 0]);
        if (p[2] <= 0.01) { started = false; continue; }
        if (started) ctx.lineTo(p[0], p[1]); else { ctx.moveTo(p[0], p[1]); started = true; }
      }
      ctx.stroke();
      ctx.globalAlpha = 1;
    });
    // Every half box's faces, far to near.
    const faces = [];
    o.poses.forEach((pose, i) => {
      const s = o.shapes[i];
      if (!s) return;
      const [hx, hy, hz] = s.size.map((v) => v / 2);
      for (const [x0, x1] of [[0, hx], [-hx, 0]]) {
        const corners = [];
        for (const x of [x0, x1]) for (const y of [-hy, hy]) for (const z of [-hz, hz])
          corners.push(worldPoint(s, pose, [x, y, z], x0 < 0));
        for (const f of kBoxFaces) {
          const w = f.map((k) => corners[k]);
          const n = norm(cross(sub(w[1], w[0]), sub(w[3], w[0])));
          const centre = w.reduce((a, b) => add(a, b)).map((c) => c / 4);
          if (dot(n, sub(eye, centre)) <= 0) continue;  // facing away
          const pts = w.map((p) => project(canvas, p));
          if (pts.some((p) => p[2] <= 0.01)) continue;
          faces.push({ pts, depth: dot(sub(centre, eye), fwd), shade: 0.55 + 0.45 * Math.max(0, dot(n, light)), i });
        }
      }
    });
    faces.sort((a, b) => b.depth - a.depth);
    for (const f of faces) {
      ctx.fillStyle = palette[f.i % palette.length];
      ctx.globalAlpha = 1;
      ctx.beginPath();
      ctx.moveTo(f.pts[0][0], f.pts[0][1]);
      for (let k = 1; k < 4; ++k) ctx.lineTo(f.pts[k][0], f.pts[k][1]);
      ctx.closePath();
      ctx.fill();
      ctx.fillStyle = `rgba(0,0,0,${(1 - f.shade).toFixed(3)})`;
      ctx.fill();
      ctx.strokeStyle = f.i === selected ? '#000' : 'rgba(0,0,0,0.35)';
      ctx.lineWidth = f.i === selected ? 2 : 1;
      ctx.stroke();
    }
    // Docked connectors: a red bar between them.
    ctx.strokeStyle = '#d00';
    ctx.lineWidth = 4;
    for (const [a, ca, b, cb] of o.docked) {
      if (!o.poses[a] || !o.poses[b]) continue;
      const p = project(canvas, worldPoint(o.shapes[a], o.poses[a], o.shapes[a].connectors[ca].p));
      const q = project(canvas, worldPoint(o.shapes[b], o.poses[b], o.shapes[b].connectors[cb].p));
      ctx.beginPath(); ctx.moveTo(p[0], p[1]); ctx.lineTo(q[0] + 0.5, q[1] + 0.5); ctx.stroke();
    }
    ctx.lineWidth = 1;
    // Names above the modules.
    ctx.fillStyle = '#000';
    ctx.font = '12px system-ui, sans-serif';
    o.poses.forEach((pose, i) => {
      const s = o.shapes[i];
      if (!s) return;
      const p = project(canvas, add(pose.p, [0, 0, s.size[2]]));
      if (p[2] > 0.01) ctx.fillText(s.name, p[0] - 10, p[1] - 4);
    });
  }

  // The module whose centre is drawn nearest to (x, y) on the canvas, or -1.
  function pick(o, canvas, x, y) {
    let best = -1, bestD = Infinity;
    o.poses.forEach((pose, i) => {
      const p = project(canvas, pose.p);
      const d = (p[0] - x) ** 2 + (p[1] - y) ** 2;
      if (p[2] > 0.01 && d < bestD) { bestD = d; best = i; }
    });
    return best;
  }

  function orbit(dx, dy) {
    cam.az -= dx * 0.01;
    cam.el = Math.min(1.5, Math.max(0.05, cam.el + dy * 0.01));
  }
  function zoom(factor) { cam.dist = Math.min(50, Math.max(0.1, cam.dist * factor)); }

  // "a.front - b.back" per docked pair.
  function topology(o) {
    return o.docked.map(([a, ca, b, cb]) => {
      const A = o.shapes[a], B = o.shapes[b];
      return A && B ? `${A.name}.${A.connectors[ca].name} \u2013 ${B.name}.${B.connectors[cb].name}` : '';
    });
  }

  return { state, hello, frame, draw, pick, orbit, zoom, topology };
})();
