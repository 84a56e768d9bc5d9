// The runtime muscle rig in JavaScript: the same equations as runtime/muscle_rig.cpp, in float64 (JS
// numbers), one function per equation, each commented with the C++ function it mirrors. No three.js
// here: joint matrices are plain arrays of 16 numbers, column-major as glTF stores them (m[12], m[13],
// m[14] is the translation). docs/extensions/RIGBAKE_muscle_rig.md states the equations.
//
// A test (tests/view_test.cpp) evaluates this code in headless Chromium at sampled frames of every
// clip and compares it with runtime::MuscleRigJob<double>: any change here must keep the two equal.

// runtime/muscle_rig.cpp kMinLengthFraction: below this fraction of the rest length the fibre has no
// direction and the carried rest fibre stands in.
export const MIN_LENGTH_FRACTION = 1e-6;
// runtime/muscle_rig.cpp kReversedFibre: 1 + cos(angle) below which the fibre has reversed.
export const REVERSED_FIBRE = 1e-12;

// ---- vector helpers (runtime/muscle_rig.cpp Vec3 operators) ----

const add = (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
const scale = (s, a) => [s * a[0], s * a[1], s * a[2]];
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
const length = (a) => Math.sqrt(dot(a, a));
// normalized(): a zero vector stays zero.
function normalized(a) {
  const n = length(a);
  return n > 0 ? scale(1 / n, a) : a;
}

// transformPoint(m, p): m * (p, 1).
export function transformPoint(m, p) {
  return [
    m[0] * p[0] + m[4] * p[1] + m[8] * p[2] + m[12],
    m[1] * p[0] + m[5] * p[1] + m[9] * p[2] + m[13],
    m[2] * p[0] + m[6] * p[1] + m[10] * p[2] + m[14],
  ];
}

// transformDirection(m, d): m * (d, 0).
export function transformDirection(m, d) {
  return [
    m[0] * d[0] + m[4] * d[1] + m[8] * d[2],
    m[1] * d[0] + m[5] * d[1] + m[9] * d[2],
    m[2] * d[0] + m[6] * d[1] + m[10] * d[2],
  ];
}

// multiplyAffine(a, b) (runtime/affine.h; evaluateSkinned sums each entry in the same order): a * b
// for column-major affine 4x4 matrices (last row 0 0 0 1), written into `out` term by term in the C++
// order, so that the two round alike.
export function multiplyAffine(a, b, out = new Array(16)) {
  for (let c = 0; c < 4; ++c) {
    for (let r = 0; r < 3; ++r) {
      out[c * 4 + r] = a[r] * b[c * 4] + a[4 + r] * b[c * 4 + 1] + a[8 + r] * b[c * 4 + 2] + (c === 3 ? a[12 + r] : 0);
    }
    out[c * 4 + 3] = c === 3 ? 1 : 0;
  }
  return out;
}

// storeFrame(x, y, z, position): the matrix with those columns.
function storeFrame(x, y, z, position, out, offset) {
  const values = [x[0], x[1], x[2], 0, y[0], y[1], y[2], 0, z[0], z[1], z[2], 0, position[0], position[1], position[2], 1];
  for (let k = 0; k < 16; ++k) out[offset + k] = values[k];
}

// ---- quaternions (x, y, z, w), for the jiggle and the player ----

// rotationOf(m) (for the jiggle and the player): the rotation of a joint matrix as a unit quaternion.
// The columns are made orthonormal first (Gram-Schmidt: x, then y without its x part, z = x cross y),
// then Shepperd's method ("Quaternion from rotation matrix", J. Guidance and Control 1(3), 1978) picks
// the largest of trace, x.x, y.y, z.z to divide by.
export function rotationOf(m) {
  const x = normalized([m[0], m[1], m[2]]);
  const y0 = [m[4], m[5], m[6]];
  const y = normalized(sub(y0, scale(dot(y0, x), x)));
  const z = cross(x, y);
  const trace = x[0] + y[1] + z[2];
  if (trace > 0) {
    const s = Math.sqrt(trace + 1) * 2;
    return [(y[2] - z[1]) / s, (z[0] - x[2]) / s, (x[1] - y[0]) / s, 0.25 * s];
  }
  if (x[0] > y[1] && x[0] > z[2]) {
    const s = Math.sqrt(1 + x[0] - y[1] - z[2]) * 2;
    return [0.25 * s, (y[0] + x[1]) / s, (z[0] + x[2]) / s, (y[2] - z[1]) / s];
  }
  if (y[1] > z[2]) {
    const s = Math.sqrt(1 + y[1] - x[0] - z[2]) * 2;
    return [(y[0] + x[1]) / s, 0.25 * s, (z[1] + y[2]) / s, (z[0] - x[2]) / s];
  }
  const s = Math.sqrt(1 + z[2] - x[0] - y[1]) * 2;
  return [(z[0] + x[2]) / s, (z[1] + y[2]) / s, 0.25 * s, (x[1] - y[0]) / s];
}

// clampValue(v, lo, hi).
const clampValue = (v, lo, hi) => (v < lo ? lo : v > hi ? hi : v);

// ---- the equations ----

// Locators (evaluateLocators): the origin and insertion ride their attach joints,
//   o = W_origin * originLocal,   i = W_insertion * insertionLocal.
export function locators(muscle, joints) {
  return {
    origin: transformPoint(joints[muscle.originNode], muscle.originLocal),
    insertion: transformPoint(joints[muscle.insertionNode], muscle.insertionLocal),
  };
}

// Length ratio (evaluateLocators): r = |i - o| / L_rest, and r_c = clamp(r, compression, stretch) is what
// the ratio keys are read at (the talk's createFromAttachObjs compressionFactor / stretchFactor).
export function lengthRatio(muscle, origin, insertion) {
  const ratio = length(sub(insertion, origin)) / muscle.restLength;
  return { ratio, clampedRatio: clampValue(ratio, muscle.compression, muscle.stretch) };
}

// orthonormalFrame(m) (orthonormalFrame): a joint matrix's first two columns made orthonormal (Gram-Schmidt: x, then y
// without its x part, z = x cross y), the frame the twist is read in. Returns [x, y, z].
export function orthonormalFrame(m) {
  const x = normalized([m[0], m[1], m[2]]);
  const y0 = [m[4], m[5], m[6]];
  const y = normalized(sub(y0, scale(dot(y0, x), x)));
  return [x, y, cross(x, y)];
}

// Frame.apply: the frame's columns weighted by d.
const applyFrame = (f, d) => add(add(scale(d[0], f[0]), scale(d[1], f[1])), scale(d[2], f[2]));

// twistReferencePairs (prepareMuscleRig): the twist driver's reference pair, two unit directions
// across the rest fibre a = normalize(twistAxisLocal), u1 (the coordinate axis most nearly across a,
// made perpendicular to it) and u2 = a cross u1, in the origin joint's orthonormal frame, and the same
// two taken into the insertion joint's by the bind rotation, v_k = Q0^-1 u_k (Q0 = insertionBindInOrigin
// made unit). Returns {origin: [u1, u2], insertion: [v1, v2]}.
export function twistReferencePairs(twistAxisLocal, insertionBindInOrigin) {
  const a = normalized(twistAxisLocal);
  let u1 = [0, 0, 0];
  let u2 = [0, 0, 0];
  if (dot(a, a) > 0) {
    const [ax, ay, az] = a.map(Math.abs);
    const axis = ax <= ay && ax <= az ? [1, 0, 0] : ay <= az ? [0, 1, 0] : [0, 0, 1];
    u1 = normalized(sub(axis, scale(dot(axis, a), a)));
    u2 = cross(a, u1);
  }
  let [x, y, z, w] = insertionBindInOrigin;
  const n = Math.sqrt(x * x + y * y + z * z + w * w);
  if (n > 0) [x, y, z, w] = [x / n, y / n, z / n, w / n];
  else [x, y, z, w] = [0, 0, 0, 1];
  // B0's columns; B0^T u = (c0 . u, c1 . u, c2 . u).
  const c0 = [1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w)];
  const c1 = [2 * (x * y - z * w), 1 - 2 * (x * x + z * z), 2 * (y * z + x * w)];
  const c2 = [2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y)];
  const inInsertion = (u) => [dot(c0, u), dot(c1, u), dot(c2, u)];
  return { origin: [u1, u2], insertion: [inInsertion(u1), inInsertion(u2)] };
}

// Twist driver (evaluateTwist): the angle about the rest fibre from the origin joint's reference pair
// (u1, u2) to the insertion joint's (v1, v2), each carried by its joint's orthonormal frame,
//   theta = atan2(u2 . v1 - u1 . v2, u1 . v1 + u2 . v2), in (-pi, pi],
// the swing-twist twist of delta = R_o^-1 R_i Q0^-1 about the fibre (2 atan2(delta.xyz . a, delta.w)),
// read without quaternions (docs/runtime.md derives it). The pairs come from readMuscleRig (twistPairs).
export function twistAngle(muscle, joints) {
  const pairs = muscle.twistPairs || twistReferencePairs(muscle.twistAxisLocal, muscle.insertionBindInOrigin);
  const origin = orthonormalFrame(joints[muscle.originNode]);
  const insertion = orthonormalFrame(joints[muscle.insertionNode]);
  const [u1, u2] = pairs.origin.map((u) => applyFrame(origin, u));
  const [v1, v2] = pairs.insertion.map((v) => applyFrame(insertion, v));
  const twist = Math.atan2(dot(u2, v1) - dot(u1, v2), dot(u1, v1) + dot(u2, v2));
  return twist <= -Math.PI ? twist + 2 * Math.PI : twist;
}

// Drivers of one muscle (MuscleDrivers): the locators, the length ratio and the twist.
export function muscleDrivers(muscle, joints) {
  const { origin, insertion } = locators(muscle, joints);
  const { ratio, clampedRatio } = lengthRatio(muscle, origin, insertion);
  return { origin, insertion, ratio, clampedRatio, twist: twistAngle(muscle, joints) };
}

// One piecewise-linear response curve at `at` (addCurve): keys [at, up, side, scale] ascending; the
// nearest key holds outside them. Adds into `sum`: offsets add, scales add their difference from 1.
export function addCurve(keys, at, sum) {
  const count = keys.length;
  if (count <= 0) return;
  let value = keys[0];
  if (at >= keys[count - 1][0]) {
    value = keys[count - 1];
  } else if (at > keys[0][0]) {
    let k = 1;
    while (keys[k][0] < at) ++k; // keys[k - 1].at < at <= keys[k].at
    const a = keys[k - 1];
    const b = keys[k];
    const span = b[0] - a[0];
    const t = span > 0 ? (at - a[0]) / span : 1;
    value = [at, a[1] + t * (b[1] - a[1]), a[2] + t * (b[2] - a[2]), a[3] + t * (b[3] - a[3])];
  }
  sum.up += value[1];
  sum.side += value[2];
  sum.scale += value[3] - 1;
}

// The response (evaluateResponse): the ratio curve at r_c plus the twist curve at the twist.
export function evaluateResponse(muscle, drivers) {
  const sum = { up: 0, side: 0, scale: 1 };
  addCurve(muscle.ratioKeys, drivers.clampedRatio, sum);
  addCurve(muscle.twistKeys, drivers.twist, sum);
  return sum;
}

// The skinned joint (evaluateSkinned): M = W_carrier * K * T(0, up, side) * diag(1, s, s), K the
// skinned joint's bind transform relative to the carrier (skinnedInCarrier). Returns both M and the
// local matrix K T S (the skinned node is a child of the carrier node, so that is its node matrix).
export function skinnedMatrix(muscle, joints, response) {
  const k = muscle.skinnedInCarrier;
  const local = k.slice();
  for (let r = 0; r < 3; ++r) local[12 + r] += k[4 + r] * response.up + k[8 + r] * response.side;
  for (let r = 0; r < 3; ++r) {
    local[4 + r] *= response.scale;
    local[8 + r] *= response.scale;
  }
  return { world: multiplyAffine(joints[muscle.carrierNode], local), local };
}

// The helper frames (evaluateHelpers): base at the origin with X along the fibre, tip at the insertion
// aimed back, driver at o + fraction * L * fibre + offset_up * up + offset_side * side. The up vector
// is carried by the origin joint and swung with the fibre by the minimal rotation (Rodrigues) that
// takes the carried rest fibre to the current fibre, so it never flips. Returns 48 numbers.
export function helperFrames(muscle, joints, origin, insertion) {
  const originJoint = joints[muscle.originNode];
  const carriedFibre = normalized(transformDirection(originJoint, muscle.fibreLocal));
  const carriedUpRaw = normalized(transformDirection(originJoint, muscle.upLocal));
  const carriedUp = normalized(sub(carriedUpRaw, scale(dot(carriedUpRaw, carriedFibre), carriedFibre)));
  const segment = sub(insertion, origin);
  const current = length(segment);
  const fibre = current > MIN_LENGTH_FRACTION * muscle.restLength ? scale(1 / current, segment) : carriedFibre;
  const cosine = dot(carriedFibre, fibre);
  let swung = carriedUp;
  if (1 + cosine >= REVERSED_FIBRE) {
    const k = cross(carriedFibre, fibre);
    swung = add(add(scale(cosine, carriedUp), cross(k, carriedUp)), scale(dot(k, carriedUp) / (1 + cosine), k));
  }
  const up = normalized(sub(swung, scale(dot(swung, fibre), fibre)));
  const side = cross(fibre, up);
  const driver = add(
    add(add(origin, scale(muscle.driverFraction * current, fibre)), scale(muscle.driverOffset[0], up)),
    scale(muscle.driverOffset[1], side),
  );
  const out = new Array(48);
  storeFrame(fibre, up, side, origin, out, 0);
  storeFrame(scale(-1, fibre), up, scale(-1, side), insertion, out, 16);
  storeFrame(fibre, up, side, driver, out, 32);
  return out;
}

// One muscle for one pose: drivers, response, skinned matrix and (when asked) the helpers.
export function evaluateMuscle(muscle, joints, withHelpers = false) {
  const drivers = muscleDrivers(muscle, joints);
  const response = evaluateResponse(muscle, drivers);
  const skinned = skinnedMatrix(muscle, joints, response);
  const helpers = withHelpers ? helperFrames(muscle, joints, drivers.origin, drivers.insertion) : null;
  return { drivers, response, skinned: skinned.world, local: skinned.local, helpers };
}

// ---- the extension ----

function numberArray(value, count, where, problems) {
  if (!Array.isArray(value) || value.length !== count || !value.every((v) => typeof v === 'number' && Number.isFinite(v))) {
    problems.push(`${where}: must be an array of ${count} numbers`);
    return null;
  }
  return value.slice();
}

function keyArray(value, where, problems) {
  if (value === undefined) return [];
  if (!Array.isArray(value)) {
    problems.push(`${where}: must be an array of [at, up, side, scale] keys`);
    return [];
  }
  const keys = [];
  value.forEach((key, k) => {
    const parsed = numberArray(key, 4, `${where}/${k}`, problems);
    if (parsed) keys.push(parsed);
  });
  for (let k = 1; k < keys.length; ++k) {
    if (!(keys[k][0] > keys[k - 1][0])) problems.push(`${where}: keys are not ascending in at`);
  }
  return keys;
}

// The RIGBAKE_muscle_rig extension of a glTF JSON as plain data, node indices kept (the JS runtime
// indexes joint matrices by node). Returns {rig, problems}; rig is null when the file has none.
// Mirrors formats/muscle_rig_extension.cpp readMuscleRigExtension and runtime rigProblem().
export function readMuscleRig(json) {
  const problems = [];
  const extension = json.extensions && json.extensions.RIGBAKE_muscle_rig;
  if (!extension) return { rig: null, problems };
  const base = '/extensions/RIGBAKE_muscle_rig';
  const nodeCount = (json.nodes || []).length;
  if (extension.version !== 1) {
    problems.push(`${base}/version: must be 1`);
    return { rig: null, problems };
  }
  if (!Array.isArray(extension.muscles)) {
    problems.push(`${base}/muscles: must be an array`);
    return { rig: null, problems };
  }
  const node = (item, key, where) => {
    const index = item[key];
    if (!Number.isInteger(index) || index < 0 || index >= nodeCount) {
      problems.push(`${where}/${key}: is not a node of the file`);
      return -1;
    }
    return index;
  };
  const number = (item, key, where) => {
    if (typeof item[key] !== 'number' || !Number.isFinite(item[key])) {
      problems.push(`${where}/${key}: must be a number`);
      return NaN;
    }
    return item[key];
  };
  const muscles = extension.muscles.map((item, m) => {
    const where = `${base}/muscles/${m}`;
    const muscle = {
      name: typeof item.name === 'string' ? item.name : `muscle ${m}`,
      skinnedNode: node(item, 'skinnedNode', where),
      helperNodes: Array.isArray(item.helperNodes) ? item.helperNodes.slice() : [],
      originNode: node(item, 'originNode', where),
      insertionNode: node(item, 'insertionNode', where),
      carrierNode: node(item, 'carrierNode', where),
      originLocal: numberArray(item.originLocal, 3, `${where}/originLocal`, problems),
      insertionLocal: numberArray(item.insertionLocal, 3, `${where}/insertionLocal`, problems),
      restLength: number(item, 'restLength', where),
      compression: number(item, 'compression', where),
      stretch: number(item, 'stretch', where),
      fibreLocal: numberArray(item.fibreLocal, 3, `${where}/fibreLocal`, problems),
      upLocal: numberArray(item.upLocal, 3, `${where}/upLocal`, problems),
      twistAxisLocal: numberArray(item.twistAxisLocal, 3, `${where}/twistAxisLocal`, problems),
      insertionBindInOrigin: numberArray(item.insertionBindInOrigin, 4, `${where}/insertionBindInOrigin`, problems),
      driverFraction: number(item, 'driverFraction', where),
      driverOffset: numberArray(item.driverOffset, 2, `${where}/driverOffset`, problems),
      skinnedInCarrier: numberArray(item.skinnedInCarrier, 16, `${where}/skinnedInCarrier`, problems),
      ratioKeys: keyArray(item.ratioKeys, `${where}/ratioKeys`, problems),
      twistKeys: keyArray(item.twistKeys, `${where}/twistKeys`, problems),
    };
    if (muscle.twistAxisLocal && muscle.insertionBindInOrigin)
      muscle.twistPairs = twistReferencePairs(muscle.twistAxisLocal, muscle.insertionBindInOrigin);
    if (!(muscle.restLength > 0)) problems.push(`${where}/restLength: must be positive`);
    if (!(muscle.compression > 0 && muscle.compression <= 1 && muscle.stretch >= 1))
      problems.push(`${where}: compression / stretch are not 0 < compression <= 1 <= stretch`);
    return muscle;
  });
  const jiggles = Array.isArray(extension.jiggles) ? extension.jiggles : [];
  return { rig: problems.length ? null : { muscles, jiggles }, problems };
}
