// The RIGBAKE_muscle_rig extension evaluated from its specification alone: written from
// docs/extensions/RIGBAKE_muscle_rig.md ("Equations" 1-9) and presets/schemas/RIGBAKE_muscle_rig.schema.json,
// without reading runtime/ or player/, so that tests/doc_evaluator_test.cpp's agreement with the C++
// runtime shows the document is enough to implement the rig. Plain JavaScript numbers (float64), no
// dependency. Matrices are column-major arrays of 16 numbers (glTF's layout, translation in 12..14).
//
//   const rig = prepareMuscleRig(extensionObject);
//   const { skinned, helpers, drivers } = evaluateMuscleRig(rig, worldOf);
// worldOf(node) returns node's world matrix for the pose; skinned[m] is muscle m's skinned joint world
// matrix M (equation 8), helpers[m] its [base, tip, driver] world matrices (equation 9) or null when the
// muscle has no helperNodes, drivers[m] its { ratio, clampedRatio, twist }.

import { dot, cross, add, sub, scale, norm, normalize } from './vector.mjs';

const column = (m, j) => [m[4 * j], m[4 * j + 1], m[4 * j + 2]];
const transformPoint = (m, p) => add(add(add(scale(column(m, 0), p[0]), scale(column(m, 1), p[1])), scale(column(m, 2), p[2])), column(m, 3));
const transformDirection = (m, d) => add(add(scale(column(m, 0), d[0]), scale(column(m, 1), d[1])), scale(column(m, 2), d[2]));

function multiply(a, b) {
  const out = new Array(16).fill(0);
  for (let c = 0; c < 4; ++c)
    for (let r = 0; r < 4; ++r) {
      let sum = 0;
      for (let k = 0; k < 4; ++k) sum += a[4 * k + r] * b[4 * c + k];
      out[4 * c + r] = sum;
    }
  return out;
}

function matrixOfColumns(x, y, z, t) {
  return [x[0], x[1], x[2], 0, y[0], y[1], y[2], 0, z[0], z[1], z[2], 0, t[0], t[1], t[2], 1];
}

// Equation 3: R̂(W) = [x y z] by Gram-Schmidt on the first two columns; the third is ignored. Returned as
// its three columns.
function orthonormalFrame(w) {
  const x = normalize(column(w, 0));
  const c1 = column(w, 1);
  const y = normalize(sub(c1, scale(x, dot(c1, x))));
  return [x, y, cross(x, y)];
}
const applyFrame = (frame, v) => add(add(scale(frame[0], v[0]), scale(frame[1], v[1])), scale(frame[2], v[2]));

// The rotation matrix of a quaternion (x, y, z, w), made unit first; a zero quaternion is the identity
// (equation 4). Returned as its three columns.
function quaternionColumns(q) {
  const length = Math.hypot(q[0], q[1], q[2], q[3]);
  if (length === 0) return [[1, 0, 0], [0, 1, 0], [0, 0, 1]];
  const [x, y, z, w] = q.map((v) => v / length);
  return [
    [1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w)],
    [2 * (x * y - z * w), 1 - 2 * (x * x + z * z), 2 * (y * z + x * w)],
    [2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y)],
  ];
}

// Equation 4's once-per-rig part: the reference pairs u1, u2 (origin frame) and v1, v2 (insertion frame).
function twistReferencePairs(axis, q0) {
  const zero = [0, 0, 0];
  if (norm(axis) === 0) return { u1: zero, u2: zero, v1: zero, v2: zero };
  const a = normalize(axis);
  const abs = a.map(Math.abs);
  const k = abs[0] <= abs[1] && abs[0] <= abs[2] ? 0 : abs[1] <= abs[2] ? 1 : 2;
  const e = [0, 0, 0];
  e[k] = 1;
  const u1 = normalize(sub(e, scale(a, dot(e, a))));
  const u2 = cross(a, u1);
  // v = B0ᵀ u: the dot products of u with B0's columns.
  const b0 = quaternionColumns(q0);
  const transposeTimes = (u) => [dot(b0[0], u), dot(b0[1], u), dot(b0[2], u)];
  return { u1, u2, v1: transposeTimes(u1), v2: transposeTimes(u2) };
}

// Equation 5, the search form: the keys' [up, side, scale] at x, or null for an empty curve.
function readCurve(keys, x) {
  if (keys.length === 0) return null;
  const values = (key) => key.slice(1, 4);
  if (x <= keys[0][0]) return values(keys[0]);
  const last = keys[keys.length - 1];
  if (x >= last[0]) return values(last);
  let j = 1;
  while (!(keys[j - 1][0] < x && x <= keys[j][0])) ++j;
  const u = (x - keys[j - 1][0]) / (keys[j][0] - keys[j - 1][0]);
  return [0, 1, 2].map((c) => keys[j - 1][c + 1] + u * (keys[j][c + 1] - keys[j - 1][c + 1]));
}

export function prepareMuscleRig(extension) {
  if (extension.version !== 1) throw new Error(`RIGBAKE_muscle_rig: version ${extension.version}, this evaluator reads 1`);
  return extension.muscles.map((m) => ({
    ...m,
    ratioKeys: m.ratioKeys ?? [],
    twistKeys: m.twistKeys ?? [],
    pairs: twistReferencePairs(m.twistAxisLocal, m.insertionBindInOrigin),
  }));
}

// Equation 9: the base, tip and driver helper world matrices.
function helperMatrices(m, wo, o, i) {
  const f0 = normalize(transformDirection(wo, m.fibreLocal));
  const uc = normalize(transformDirection(wo, m.upLocal));
  const u0 = normalize(sub(uc, scale(f0, dot(uc, f0))));
  const d = sub(i, o);
  const length = norm(d);
  const f = length > 1e-6 * m.restLength ? scale(d, 1 / length) : f0;
  const k = cross(f0, f);
  const cosine = dot(f0, f);
  const swung = 1 + cosine < 1e-12 ? u0 : add(add(scale(u0, cosine), cross(k, u0)), scale(k, dot(k, u0) / (1 + cosine)));
  const up = normalize(sub(swung, scale(f, dot(swung, f))));
  const side = cross(f, up);
  const p = add(add(add(o, scale(f, m.driverFraction * length)), scale(up, m.driverOffset[0])), scale(side, m.driverOffset[1]));
  return [
    matrixOfColumns(f, up, side, o),
    matrixOfColumns(scale(f, -1), up, scale(side, -1), i),
    matrixOfColumns(f, up, side, p),
  ];
}

export function evaluateMuscleRig(rig, worldOf) {
  const skinned = [], helpers = [], drivers = [];
  for (const m of rig) {
    const wo = worldOf(m.originNode), wi = worldOf(m.insertionNode), wc = worldOf(m.carrierNode);
    // Equations 1-2.
    const o = transformPoint(wo, m.originLocal);
    const i = transformPoint(wi, m.insertionLocal);
    const ratio = norm(sub(i, o)) / m.restLength;
    const clampedRatio = Math.min(Math.max(ratio, m.compression), m.stretch);
    // Equations 3-4.
    const ro = orthonormalFrame(wo), ri = orthonormalFrame(wi);
    const { u1, u2, v1, v2 } = m.pairs;
    const ou1 = applyFrame(ro, u1), ou2 = applyFrame(ro, u2), iv1 = applyFrame(ri, v1), iv2 = applyFrame(ri, v2);
    let twist = Math.atan2(dot(ou2, iv1) - dot(ou1, iv2), dot(ou1, iv1) + dot(ou2, iv2));
    if (twist === -Math.PI) twist = Math.PI;
    // Equations 5-6.
    let up = 0, side = 0, s = 1;
    for (const response of [readCurve(m.ratioKeys, clampedRatio), readCurve(m.twistKeys, twist)]) {
      if (!response) continue;
      up += response[0];
      side += response[1];
      s += response[2] - 1;
    }
    // Equation 7: K' = K · T(0, up, side) · diag(1, s, s).
    const k = m.skinnedInCarrier;
    const k1 = column(k, 1), k2 = column(k, 2);
    const translation = add(add(column(k, 3), scale(k1, up)), scale(k2, side));
    const local = matrixOfColumns(column(k, 0), scale(k1, s), scale(k2, s), translation);
    // Equation 8.
    skinned.push(multiply(wc, local));
    helpers.push(m.helperNodes ? helperMatrices(m, wo, o, i) : null);
    drivers.push({ ratio, clampedRatio, twist });
  }
  return { skinned, helpers, drivers };
}
