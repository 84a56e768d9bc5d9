// Live jiggle joints: the damped spring of pipeline/jiggle.cpp (docs/jiggle.md), run on a fixed
// 1/240 s step that carries the leftover time from frame to frame ("simulated at a fixed frame time,
// regardless of the hardware"), with hit impulses as calls. Float64, no three.js: frames are
// {translation: [x, y, z], rotation: [x, y, z, w]} and the spring state lives in world space.
//
// The bake (pipeline/jiggle.cpp simulate) knows the whole clip and samples the animation at every
// step; a live player only knows the frames it has rendered, so each step's target is interpolated
// between the previous and the current rendered frame (translation linearly, rotation by slerp), and
// the pose shown is the spring state blended between the last two steps (the state lags by less than
// one step, 4.2 ms). Everything else is the bake's equations.

import { rotationOf } from './muscle_rig.js';

// pipeline/jiggle.h constants.
export const JIGGLE_TIMESTEP = 1 / 240;
export const MIN_JIGGLE_HZ = 1;
export const MAX_JIGGLE_HZ = 12;
export const MIN_DAMPING_RATIO = 0.02;
export const MIN_CLAMP_DEG = 0.01;
export const MAX_JIGGLE_OFFSET = 1.5;
// pipeline/jiggle.cpp kAimDegenerateSin.
const AIM_DEGENERATE_SIN = 1e-6;
// At most this many steps per rendered frame (a tab left in the background for a minute must not
// simulate a minute at once when it comes back): the rest of the time is dropped.
const MAX_STEPS_PER_FRAME = 240;

const DEGREE = Math.PI / 180;
const add = (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
const scale = (s, a) => [s * a[0], s * a[1], s * a[2]];
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
const norm = (a) => Math.sqrt(dot(a, a));
const unit = (a) => {
  const n = norm(a);
  return n > 0 ? scale(1 / n, a) : a;
};
const same = (a, b) => a[0] === b[0] && a[1] === b[1] && a[2] === b[2];

// q * v * q^-1 for a unit quaternion (x, y, z, w).
export function rotate(q, v) {
  const u = [q[0], q[1], q[2]];
  const t = scale(2, cross(u, v));
  return add(add(v, scale(q[3], t)), cross(u, t));
}
const conjugate = (q) => [-q[0], -q[1], -q[2], q[3]];

// Spherical interpolation on the short arc (glTF's rotation interpolation).
export function slerp(a, b, t) {
  let d = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
  let c = b;
  if (d < 0) {
    d = -d;
    c = [-b[0], -b[1], -b[2], -b[3]];
  }
  let wa = 1 - t;
  let wb = t;
  if (d < 0.9995) {
    const angle = Math.acos(d);
    const s = Math.sin(angle);
    wa = Math.sin((1 - t) * angle) / s;
    wb = Math.sin(t * angle) / s;
  }
  const q = [wa * a[0] + wb * c[0], wa * a[1] + wb * c[1], wa * a[2] + wb * c[2], wa * a[3] + wb * c[3]];
  const n = Math.hypot(q[0], q[1], q[2], q[3]);
  return q.map((x) => x / n);
}

// springConstants (docs/jiggle.md "Stiffness and damping -> k and beta"):
//   f = 1 Hz * 12^stiffness, omega = 2 pi f, k = omega^2, zeta = 0.02 + 0.98 damping, beta = 2 zeta omega.
export function springConstants(stiffness, damping) {
  const frequency = MIN_JIGGLE_HZ * Math.pow(MAX_JIGGLE_HZ / MIN_JIGGLE_HZ, stiffness);
  const omega = 2 * Math.PI * frequency;
  const zeta = MIN_DAMPING_RATIO + (1 - MIN_DAMPING_RATIO) * damping;
  return { k: omega * omega, beta: 2 * zeta * omega };
}

// The elliptical cone (pipeline/jiggle.cpp Cone): in (major, aim, minor) = (x, y, z) coordinates,
// G = x^2 cos^2 a sin^2 b + z^2 cos^2 b sin^2 a - y^2 sin^2 a sin^2 b; inside <=> G <= 0 and y >= 0.
export function makeCone(setup) {
  const aim = setup.aimAxis;
  const major = setup.majorAxis;
  const minor = cross(aim, major);
  const a = Math.max(setup.clampMajorDeg, MIN_CLAMP_DEG) * DEGREE;
  const b = Math.max(setup.clampMinorDeg, MIN_CLAMP_DEG) * DEGREE;
  const sa = Math.sin(a), ca = Math.cos(a), sb = Math.sin(b), cb = Math.cos(b);
  return {
    aim, major, minor, sa, ca, sb, cb,
    gx: ca * ca * sb * sb,
    gz: cb * cb * sa * sa,
    gy: sa * sa * sb * sb,
  };
}
const coneCoords = (cone, q) => [dot(q, cone.major), dot(q, cone.aim), dot(q, cone.minor)];
const coneValue = (cone, c) => cone.gx * c[0] * c[0] + cone.gz * c[2] * c[2] - cone.gy * c[1] * c[1];
const coneInside = (cone, c) => c[1] >= 0 && coneValue(cone, c) <= 0;
// Outward normal grad G in the joint's frame.
const coneNormal = (cone, c) =>
  scale(2, add(add(scale(cone.gx * c[0], cone.major), scale(-cone.gy * c[1], cone.aim)), scale(cone.gz * c[2], cone.minor)));

// clampToCone (the talk's line - elliptical cone intersection): a point q outside the cone moves along
// the segment from the rest point L * aim to q onto the surface, the smallest root in (0, 1] of
// A t^2 + B t + C = 0, refined by bisection so that the result is inside and clamping it again
// changes nothing. Points inside are returned unchanged.
export function clampToCone(setup, cone, q) {
  const c1 = coneCoords(cone, q);
  if (coneInside(cone, c1)) return q;
  const L = setup.length;
  const d = [c1[0], c1[1] - L, c1[2]];
  const a = cone.gx * d[0] * d[0] + cone.gz * d[2] * d[2] - cone.gy * d[1] * d[1];
  const b = -2 * cone.gy * d[1] * L;
  const c = -cone.gy * L * L;
  let t = -1;
  const consider = (root) => {
    if (Number.isFinite(root) && root > 0 && root <= 1 && (t < 0 || root < t)) t = root;
  };
  if (Math.abs(a) <= 1e-300) {
    consider(-c / b);
  } else {
    const discriminant = b * b - 4 * a * c;
    if (discriminant >= 0) {
      const half = -0.5 * (b + Math.sign(b || 1) * Math.sqrt(discriminant));
      consider(half / a);
      if (half !== 0) consider(c / half);
    }
  }
  const rest = scale(L, setup.aimAxis);
  const insideAt = (s) => coneInside(cone, coneCoords(cone, add(rest, scale(s, sub(q, rest)))));
  let inside = 0;
  let outside = 1;
  if (t > 0) {
    const low = t * (1 - 1e-6);
    const high = Math.min(1, t * (1 + 1e-6));
    if (insideAt(low) && !insideAt(high)) {
      inside = low;
      outside = high;
    }
  }
  for (let i = 0; i < 200; ++i) {
    const middle = 0.5 * (inside + outside);
    if (middle <= inside || middle >= outside) break;
    if (insideAt(middle)) inside = middle;
    else outside = middle;
  }
  return add(rest, scale(inside, sub(q, rest)));
}

// The shortest-arc rotation from unit a to unit b (Eigen's Quaternion::FromTwoVectors).
function fromTwoVectors(a, b) {
  const c = dot(a, b);
  if (c < -1 + 1e-12) {
    // Opposite: any axis perpendicular to a.
    let axis = cross(a, [1, 0, 0]);
    if (norm(axis) < 1e-6) axis = cross(a, [0, 1, 0]);
    axis = unit(axis);
    return [axis[0], axis[1], axis[2], 0];
  }
  const axis = cross(a, b);
  const s = Math.sqrt((1 + c) * 2);
  return [axis[0] / s, axis[1] / s, axis[2] / s, s / 2];
}

// aimRotation (the talk's aim transformation): u = q / |q|, the frame [u, v, w] with w = u x up,
// v = w x u for the jiggle point and for the rest direction, D = F(u) F(aim)^T; identity at rest, the
// shortest arc when the aim or u is within 1e-6 (sine) of the up vector.
export function aimRotation(setup, q, up) {
  const rest = scale(setup.length, setup.aimAxis);
  if (same(q, rest) || norm(q) === 0) return [0, 0, 0, 1];
  const u = unit(q);
  const a = setup.aimAxis;
  const upUnit = unit(up);
  if (norm(cross(u, upUnit)) < AIM_DEGENERATE_SIN || norm(cross(a, upUnit)) < AIM_DEGENERATE_SIN) return fromTwoVectors(a, u);
  const frame = (aim) => {
    const w = unit(cross(aim, upUnit));
    const v = cross(w, aim);
    return [aim, v, w]; // columns
  };
  const fu = frame(u);
  const fa = frame(a);
  // R = F(u) F(a)^T, column-major in a 4x4 for rotationOf (already orthonormal: Gram-Schmidt keeps it).
  const m = new Array(16).fill(0);
  for (let col = 0; col < 3; ++col) {
    for (let row = 0; row < 3; ++row) {
      let sum = 0;
      for (let k = 0; k < 3; ++k) sum += fu[k][row] * fa[k][col];
      m[col * 4 + row] = sum;
    }
  }
  m[15] = 1;
  return rotationOf(m);
}

// One jiggle of the extension, live. `setup` holds the extension's jiggle entry.
export class LiveJiggle {
  constructor(setup) {
    this.setup = setup;
    this.cone = makeCone(setup);
    this.spring = springConstants(setup.stiffness, setup.damping);
    this.restPoint = scale(setup.length, setup.aimAxis);
    this.reset();
  }

  reset() {
    this.started = false;
    this.leftover = 0;
    this.kick = [0, 0, 0];
  }

  // A hit: `velocity` (m/s, world) is added to the jiggle point's velocity at the next step
  // (docs/jiggle.md "Hit reactions").
  hit(velocity) {
    this.kick = add(this.kick, velocity);
  }

  target(frame) {
    return add(frame.translation, rotate(frame.rotation, this.restPoint));
  }

  // The distance limit and the cone at a step (pipeline/jiggle.cpp simulate, `constrain`): moves p
  // back and drops the outward part of the velocity relative to the target. Returns the offset in the
  // jiggling joint's frame.
  constrain(frame, targetVelocity) {
    const r = this.target(frame);
    let offset = sub(this.p, r);
    const distance = norm(offset);
    const maxOffset = MAX_JIGGLE_OFFSET * this.setup.length;
    if (distance > maxOffset) {
      const outward = scale(1 / distance, offset);
      offset = scale(maxOffset, outward);
      this.p = add(r, offset);
      const away = dot(sub(this.v, targetVelocity), outward);
      if (away > 0) this.v = sub(this.v, scale(away, outward));
    }
    let local = rotate(conjugate(frame.rotation), offset);
    const q = add(this.restPoint, local);
    const clamped = clampToCone(this.setup, this.cone, q);
    if (!same(clamped, q)) {
      local = sub(clamped, this.restPoint);
      this.p = add(r, rotate(frame.rotation, local));
      const normal = rotate(frame.rotation, coneNormal(this.cone, coneCoords(this.cone, clamped)));
      if (norm(normal) > 0) {
        const outward = unit(normal);
        const away = dot(sub(this.v, targetVelocity), outward);
        if (away > 0) this.v = sub(this.v, scale(away, outward));
      }
    }
    return local;
  }

  // Advances by dt seconds to `frame` (the jiggling joint's animated world translation and rotation).
  // Returns the offset of the jiggle point in the joint's frame to show now.
  advance(frame, dt) {
    if (!this.started) {
      // Start at rest on the target (pipeline: "the jiggle starts on its target moving with it").
      this.started = true;
      this.previousFrame = frame;
      this.p = this.target(frame);
      this.v = [0, 0, 0];
      this.stepFrame = frame;
      this.offset = this.constrain(frame, [0, 0, 0]);
      this.previousOffset = this.offset;
      return this.offset;
    }
    const h = JIGGLE_TIMESTEP;
    const { k, beta } = this.spring;
    const start = this.previousFrame;
    let time = this.leftover; // seconds of this frame already simulated by the last step (<= 0)
    let steps = 0;
    while (dt > 0 && time + h <= dt + 1e-12 && steps < MAX_STEPS_PER_FRAME) {
      const s = Math.min(1, (time + h) / dt);
      const next = {
        translation: add(scale(1 - s, start.translation), scale(s, frame.translation)),
        rotation: slerp(start.rotation, frame.rotation, s),
      };
      // Semi-implicit Euler on x = p - r (docs/jiggle.md "Fixed timestep"): velocity first, damping
      // on the velocity relative to the target, then the position with the new velocity.
      const r = this.target(this.stepFrame);
      const targetVelocity = scale(1 / h, sub(this.target(next), r));
      this.v = add(this.v, scale(h, sub(scale(-k, sub(this.p, r)), scale(beta, sub(this.v, targetVelocity)))));
      this.p = add(this.p, scale(h, this.v));
      this.v = add(this.v, this.kick);
      this.kick = [0, 0, 0];
      this.previousOffset = this.offset;
      this.offset = this.constrain(next, targetVelocity);
      this.stepFrame = next;
      time += h;
      ++steps;
    }
    if (steps === MAX_STEPS_PER_FRAME) time = dt; // drop what a stalled tab would owe
    this.leftover = time - dt; // in (-h, 0]: the next frame starts this far before its own start
    this.previousFrame = frame;
    // The state one step ago, blended between the last two steps ("fix your timestep": a constant lag
    // of h; the cone is convex, so the blend of two clamped offsets stays inside it).
    const alpha = Math.min(1, Math.max(0, -this.leftover / h));
    return add(scale(1 - alpha, this.previousOffset), scale(alpha, this.offset));
  }

  // The jiggle rotation D in the joint's frame for an offset, with the root's up axis (world
  // rotation of the root joint `rootRotation`, the pivot's `pivotRotation`).
  rotationFor(offset, pivotRotation, rootRotation) {
    const q = clampToCone(this.setup, this.cone, add(this.restPoint, offset));
    const up = rotate(conjugate(pivotRotation), rotate(rootRotation, this.setup.rootUp));
    return aimRotation(this.setup, q, up);
  }
}

