// The RIGBAKE_muscle_rig jiggles (equation 10 of docs/extensions/RIGBAKE_muscle_rig.md, "Jiggles")
// stepped from the document alone, without reading runtime/ or player/, so that
// tests/doc_evaluator_test.cpp's agreement with the C++ JiggleJob<double> shows the section is enough to
// implement them. Plain JavaScript numbers (float64). Matrices are column-major arrays of 16 numbers.
//
//   const jiggles = prepareJiggles(extension.jiggles);   // settings (10, "Settings") and fresh states
//   startJiggle(j, worldOf)                                // 10a, a reset at rest
//   startJiggle(j, worldOf, { worldOf: other, delta })     // 10a, a reset moving with the target
//   hitJiggle(j, direction, magnitude)                     // "Hits"
//   const { correction, point, world } = stepJiggle(j, worldOf, dt, maxSteps);  // 10b-10g for one frame
//                                                          // (maxSteps 0 or absent: no cap)
// worldOf(node) returns node's world matrix of the un-jiggled pose (muscle skinned nodes: M of equation 8).

import { dot, cross, add, sub, scale, norm, normalize } from './vector.mjs';

const H = 1 / 240;
const TOL = 1e-9;
const EPS = Number.EPSILON;

// A 3x3 matrix as its three columns.
const apply = (cols, v) => add(add(scale(cols[0], v[0]), scale(cols[1], v[1])), scale(cols[2], v[2]));
const applyTransposed = (cols, v) => [dot(cols[0], v), dot(cols[1], v), dot(cols[2], v)];
const det = (c) => dot(c[0], cross(c[1], c[2]));

// The inverse transpose of a 3x3 (columns): cofactors over the determinant.
function inverseTranspose(c) {
  const d = det(c);
  return [scale(cross(c[1], c[2]), 1 / d), scale(cross(c[2], c[0]), 1 / d), scale(cross(c[0], c[1]), 1 / d)];
}

function quaternionOfColumns(c) {
  // Standard conversion, on the largest of the trace and the diagonal.
  const m00 = c[0][0], m11 = c[1][1], m22 = c[2][2];
  const m10 = c[0][1], m20 = c[0][2], m01 = c[1][0], m21 = c[1][2], m02 = c[2][0], m12 = c[2][1];
  const trace = m00 + m11 + m22;
  let q;
  if (trace > 0) {
    const s = 2 * Math.sqrt(trace + 1);
    q = [(m21 - m12) / s, (m02 - m20) / s, (m10 - m01) / s, s / 4];
  } else if (m00 >= m11 && m00 >= m22) {
    const s = 2 * Math.sqrt(1 + m00 - m11 - m22);
    q = [s / 4, (m01 + m10) / s, (m02 + m20) / s, (m21 - m12) / s];
  } else if (m11 >= m22) {
    const s = 2 * Math.sqrt(1 + m11 - m00 - m22);
    q = [(m01 + m10) / s, s / 4, (m12 + m21) / s, (m02 - m20) / s];
  } else {
    const s = 2 * Math.sqrt(1 + m22 - m00 - m11);
    q = [(m02 + m20) / s, (m12 + m21) / s, s / 4, (m10 - m01) / s];
  }
  const l = Math.hypot(...q);
  return q.map((x) => x / l);
}

function columnsOfQuaternion(q) {
  const l = Math.hypot(...q);
  const [x, y, z, w] = q.map((v) => v / l);
  return [
    [1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w)],
    [2 * (x * y - z * w), 1 - 2 * (x * x + z * z), 2 * (y * z + x * w)],
    [2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y)],
  ];
}

// "Rigid frames": translation and the nearest rotation (polar factor by Newton's iteration) as a quaternion.
function rigidOf(w) {
  const t = [w[12], w[13], w[14]];
  let x = [0, 1, 2].map((j) => normalize([w[4 * j], w[4 * j + 1], w[4 * j + 2]]));
  if (det(x) < 0) x[0] = scale(x[0], -1);
  for (let iteration = 0; iteration < 100; ++iteration) {
    const it = inverseTranspose(x);
    const next = [0, 1, 2].map((j) => scale(add(x[j], it[j]), 0.5));
    let change = 0;
    for (let j = 0; j < 3; ++j) for (let i = 0; i < 3; ++i) change = Math.max(change, Math.abs(next[j][i] - x[j][i]));
    x = next;
    if (change <= 4 * EPS) break;
  }
  const q = quaternionOfColumns(x);
  return { t, q, r: columnsOfQuaternion(q) };
}

export function prepareJiggles(items) {
  return items.map((item) => {
    const a = item.aimAxis, m = item.majorAxis, n = cross(a, m), L = item.length;
    const omega = 2 * Math.PI * Math.pow(12, item.stiffness);
    const zeta = 0.02 + 0.98 * item.damping;
    const alpha = (Math.max(item.clampMajorDeg, 0.01) * Math.PI) / 180;
    const gamma = (Math.max(item.clampMinorDeg, 0.01) * Math.PI) / 180;
    const sa = Math.sin(alpha) ** 2, sg = Math.sin(gamma) ** 2;
    return {
      node: item.node, parent: item.parentNode, root: item.rootNode, rootUp: item.rootUp, a, m, n, L, r0: scale(a, L),
      k: omega * omega, beta: 2 * zeta * omega,
      gx: Math.cos(alpha) ** 2 * sg, gz: Math.cos(gamma) ** 2 * sa, gy: sa * sg, xMax: 1.5 * L,
      state: { started: false, J: [0, 0, 0] },
    };
  });
}

// 10e: the cone clamp; returns [q', moved].
function clampToCone(j, q) {
  const coneOf = (p) => [dot(p, j.m), dot(p, j.a), dot(p, j.n)];
  const inside = (p) => {
    const c = coneOf(p);
    return c[1] >= 0 && j.gx * c[0] * c[0] + j.gz * c[2] * c[2] - j.gy * c[1] * c[1] <= 0;
  };
  if (inside(q)) return [q, false];
  const c = coneOf(q), L = j.L, d = [c[0], c[1] - L, c[2]];
  const A = j.gx * d[0] * d[0] + j.gz * d[2] * d[2] - j.gy * d[1] * d[1];
  const B = -2 * j.gy * d[1] * L, C = -j.gy * L * L;
  const roots = [];
  if (Math.abs(A) <= 1e-300) {
    if (B !== 0) roots.push(-C / B);
  } else {
    const disc = B * B - 4 * A * C;
    if (disc >= 0) {
      const s = -(B + (B >= 0 ? 1 : -1) * Math.sqrt(disc)) / 2;
      roots.push(s / A);
      if (s !== 0) roots.push(C / s);
    }
  }
  const found = roots.filter((t) => t > 0 && t <= 1).sort((x, y) => x - y);
  const along = (t) => add(j.r0, scale(sub(q, j.r0), t));
  let lo = 0, hi = 1;
  if (found.length > 0) {
    const l = found[0] * (1 - 1e-6), h = Math.min(1, found[0] * (1 + 1e-6));
    if (inside(along(l)) && !inside(along(h))) { lo = l; hi = h; }
  }
  for (let i = 0; i < 200; ++i) {
    const mid = 0.5 * (lo + hi);
    if (mid === lo || mid === hi) break;
    if (inside(along(mid))) lo = mid; else hi = mid;
  }
  return [along(lo), true];
}

// 10a. `second`, when given, is the same nodes at `delta` seconds from this pose (negative: earlier):
// the target's velocity ((t₂ − t) + R₂ r0 − R r0) / Δ becomes r'.
export function startJiggle(j, worldOf, second = null) {
  const { t, q, r } = rigidOf(worldOf(j.node));
  const s = j.state;
  let rp = [0, 0, 0];
  if (second) {
    const other = rigidOf(second.worldOf(j.node));
    rp = scale(add(sub(other.t, t), sub(apply(other.r, j.r0), apply(r, j.r0))), 1 / second.delta);
  }
  Object.assign(s, {
    started: true, x: [0, 0, 0], v: s.J, J: [0, 0, 0], rp, tau: apply(r, j.r0),
    l: [0, 0, 0], lPrev: [0, 0, 0], tLast: t, qLast: q, since: 0,
  });
}

export function hitJiggle(j, direction, magnitude) {
  j.state.J = add(j.state.J, scale(normalize(direction), magnitude));
}

// 10c-10d: one step with the step's pose relative to t_last.
function step(j, dT, rs) {
  const s = j.state;
  const target = add(dT, apply(rs, j.r0));
  const rpNew = scale(sub(target, s.tau), 1 / H);
  let v = sub(s.v, sub(rpNew, s.rp));
  v = add(v, scale(add(scale(s.x, -j.k), scale(v, -j.beta)), H));
  let x = add(s.x, scale(v, H));
  v = add(v, s.J);
  s.J = [0, 0, 0];
  const removeInward = (e) => {
    const along = dot(v, e);
    if (along > 0) v = sub(v, scale(e, along));
  };
  const length = norm(x);
  if (length > j.xMax) {
    const e = scale(x, 1 / length);
    x = scale(e, j.xMax);
    removeInward(e);
  }
  let lNew = applyTransposed(rs, x);
  const [clamped, moved] = clampToCone(j, add(j.r0, lNew));
  if (moved) {
    lNew = sub(clamped, j.r0);
    x = apply(rs, lNew);
    const c = [dot(clamped, j.m), dot(clamped, j.a), dot(clamped, j.n)];
    const gradient = scale(add(sub(scale(j.m, j.gx * c[0]), scale(j.a, j.gy * c[1])), scale(j.n, j.gz * c[2])), 2);
    removeInward(normalize(apply(rs, gradient)));
  }
  Object.assign(s, { x, v, lPrev: s.l, l: lNew, rp: rpNew, tau: target });
}

// Eigen's FromTwoVectors as 10f gives it.
function shortestArc(a, u) {
  let c = dot(a, u);
  if (c < -1 + 1e-12) {
    c = Math.max(c, -1);
    const ax = Math.abs(a[0]), ay = Math.abs(a[1]), az = Math.abs(a[2]);
    const e = ax < ay && ax < az ? [1, 0, 0] : ax < ay ? [0, 0, 1] : ay < az ? [0, 1, 0] : [0, 0, 1];
    return [...scale(normalize(cross(a, e)), Math.sqrt((1 - c) / 2)), Math.sqrt((1 + c) / 2)];
  }
  const p = Math.sqrt(2 * (1 + c));
  return [...scale(cross(a, u), 1 / p), p / 2];
}

// 10f: the correction D and the jiggle point for the offset l_out.
function output(j, worldOf, lOut, t, r) {
  const [q] = clampToCone(j, add(j.r0, lOut));
  const point = add(t, apply(r, q));
  const root = rigidOf(worldOf(j.root));
  const up = applyTransposed(r, apply(root.r, j.rootUp));
  const atRest = q[0] === j.r0[0] && q[1] === j.r0[1] && q[2] === j.r0[2];
  if (atRest || (q[0] === 0 && q[1] === 0 && q[2] === 0)) return { correction: [0, 0, 0, 1], point, atRest };
  const u = normalize(q), upUnit = normalize(up);
  if (norm(cross(u, upUnit)) < 1e-6 || norm(cross(j.a, upUnit)) < 1e-6) return { correction: shortestArc(j.a, u), point, atRest };
  const frame = (y) => {
    const w = normalize(cross(y, upUnit));
    return [y, cross(w, y), w];
  };
  const fu = frame(u), fa = frame(j.a);
  // D = F(u) F(a)^T: column c of D is sum_k F(u)_k F(a)_k[c].
  const d = [0, 1, 2].map((col) => add(add(scale(fu[0], fa[0][col]), scale(fu[1], fa[1][col])), scale(fu[2], fa[2][col])));
  return { correction: quaternionOfColumns(d), point, atRest };
}

function quaternionProduct(p, q) {
  const [px, py, pz, pw] = p, [qx, qy, qz, qw] = q;
  return [pw * qx + px * qw + py * qz - pz * qy, pw * qy - px * qz + py * qw + pz * qx, pw * qz + px * qy - py * qx + pz * qw,
    pw * qw - px * qx - py * qy - pz * qz];
}

// 10g: the jiggled world matrix of the node, P · T · (R_local · D) · S with P⁻¹ · W = T · R_local · S.
function jiggledWorld(j, worldOf, correction, atRest) {
  const w = worldOf(j.node);
  if (atRest) return w;
  const p = j.parent < 0 ? [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1] : worldOf(j.parent);
  const pc = [0, 1, 2].map((c) => [p[4 * c], p[4 * c + 1], p[4 * c + 2]]);
  // P⁻¹ = [A⁻¹, −A⁻¹ t]; A⁻¹'s rows are the inverse transpose's columns.
  const it = inverseTranspose(pc);
  const inverseApply = (v) => [dot(it[0], v), dot(it[1], v), dot(it[2], v)];
  const wc = [0, 1, 2].map((c) => [w[4 * c], w[4 * c + 1], w[4 * c + 2]]);
  const localCols = wc.map(inverseApply);
  const localT = inverseApply(sub([w[12], w[13], w[14]], [p[12], p[13], p[14]]));
  const local = [...localCols.flatMap((c) => [...c, 0]), ...localT, 1];
  const { r, q: rLocal } = rigidOf(local);
  // S = diag(s), s_c = (column c of R_local) · (column c of the local linear part): 10g's scale along
  // each rotated axis (whatever shear the local matrix has is dropped).
  const sDiagonal = [0, 1, 2].map((c) => dot(r[c], localCols[c]));
  const turned = quaternionProduct(rLocal, correction);
  const rj = columnsOfQuaternion(turned.map((v) => v / Math.hypot(...turned)));
  const jiggledCols = [0, 1, 2].map((c) => scale(rj[c], sDiagonal[c]));
  const worldCols = jiggledCols.map((c) => apply(pc, c));
  const worldT = add(apply(pc, localT), [p[12], p[13], p[14]]);
  return [...worldCols.flatMap((c) => [...c, 0]), ...worldT, 1];
}

// 10b and 10f: one frame of dt seconds (a state not started is started here, no step). With maxSteps > 0
// and more steps due, exactly maxSteps are taken at φ = m / maxSteps and the rest of the time is dropped.
export function stepJiggle(j, worldOf, dt, maxSteps = 0) {
  if (!j.state.started) startJiggle(j, worldOf);
  const s = j.state;
  const { t, q } = rigidOf(worldOf(j.node));
  const due = Math.floor((s.since + dt + TOL) / H);
  const capped = maxSteps > 0 && due > maxSteps;
  const steps = capped ? maxSteps : due;
  let lastOnFrame = false;
  for (let m = 1; m <= steps; ++m) {
    let phi = Math.min(1, (m * H - s.since) / dt);
    if (Math.abs(m * H - s.since - dt) <= TOL) phi = 1;
    if (capped) phi = m / maxSteps;
    let ts, qs;
    const unchanged = t.every((v, i) => v === s.tLast[i]) && q.every((v, i) => v === s.qLast[i]);
    if (phi >= 1 || unchanged) {
      ts = t; qs = q;
    } else {
      ts = add(s.tLast, scale(sub(t, s.tLast), phi));
      const sign = s.qLast.reduce((acc, v, i) => acc + v * q[i], 0) < 0 ? -1 : 1;
      const blend = s.qLast.map((v, i) => v + phi * (sign * q[i] - v));
      const l = Math.hypot(...blend);
      qs = blend.map((v) => v / l);
    }
    lastOnFrame = phi >= 1;
    step(j, sub(ts, s.tLast), columnsOfQuaternion(qs));
  }
  s.since = capped ? 0 : Math.max(0, s.since + dt - steps * H);
  const r = columnsOfQuaternion(q);
  s.tau = steps > 0 && lastOnFrame ? apply(r, j.r0) : sub(s.tau, sub(t, s.tLast));
  s.tLast = t;
  s.qLast = q;
  const lambda = 1 + s.since / H;
  const lOut = s.since === 0 ? s.l : add(scale(s.lPrev, 1 - lambda), scale(s.l, lambda));
  const { correction, point, atRest } = output(j, worldOf, lOut, t, r);
  return { correction, point, world: jiggledWorld(j, worldOf, correction, atRest) };
}
