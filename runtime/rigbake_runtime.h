/*
 * rigbake runtime, C API: evaluate a baked file's RIGBAKE_muscle_rig extension (muscles and jiggles)
 * from the skeleton's node world matrices, every frame. One implementation of the equations for every
 * consumer: this API wraps runtime/muscle_rig.h (MuscleRigJob) and runtime/jiggle.h (JiggleJob,
 * JiggleResetJob, applyJiggleImpulse), the code rigbake's own bake samples its channels with. Built as
 * a static library (rigbake_runtime), a shared library (librigbake_runtime.so, for Python ctypes and
 * native hosts) and WebAssembly (web/rigbake_runtime.mjs). docs/runtime.md shows a frame's calls;
 * docs/extensions/RIGBAKE_muscle_rig.md gives the equations.
 *
 * Conventions
 * - Matrices are 4x4 affine transforms of 16 floats, column-major as glTF stores them (m[12], m[13],
 *   m[14] the translation). Quaternions are 4 floats (x, y, z, w).
 * - Nodes are the glTF file's node indices. A rig is created for a file of node_count nodes, and every
 *   call that reads a pose takes node_matrices: node_count * 16 floats, node n's world matrix (the
 *   scene's space: the product of the local matrices of n and all its ancestors) at n * 16. Only the
 *   nodes the rig names are read (rigbake_rig_node_used); the others may hold anything.
 * - Every pointer the caller passes is the caller's: the library keeps none past the call, except the
 *   rig handle, which it owns until rigbake_rig_destroy. Output arrays are written only when the call
 *   succeeds; a failed call writes nothing.
 * - No call allocates after rigbake_rig_create, none throws, none does I/O, none prints.
 * - Calls on different rigs may run on different threads at once; calls on one rig must not overlap
 *   (a rig holds its jiggles' state). rigbake_last_error is per thread.
 * - Return codes: RIGBAKE_OK (0) on success, otherwise one of the RIGBAKE_ERROR_* values, with a one-line
 *   message from rigbake_last_error().
 */
#ifndef RIGBAKE_RUNTIME_H
#define RIGBAKE_RUNTIME_H

#include <stddef.h>

#if defined(RIGBAKE_RUNTIME_BUILDING_SHARED) && defined(__GNUC__)
#define RIGBAKE_RUNTIME_API __attribute__((visibility("default")))
#else
#define RIGBAKE_RUNTIME_API
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* The C API's version, major * 10000 + minor * 100 + patch: a new minor adds calls, a new major
 * changes one. rigbake_runtime_version() returns the built library's; compare with the header's. */
#define RIGBAKE_RUNTIME_VERSION 10000
/* The RIGBAKE_muscle_rig extension layout this library reads ("version" in the extension). */
#define RIGBAKE_RUNTIME_EXTENSION_VERSION 1

#define RIGBAKE_OK 0
#define RIGBAKE_ERROR_ARGUMENT 1 /* a null rig or array, an index out of range, a negative time */
#define RIGBAKE_ERROR_INVALID 2  /* the JSON text is malformed or is not a rig this library can evaluate */
#define RIGBAKE_ERROR_MEMORY 3   /* out of memory (rigbake_rig_create only) */

RIGBAKE_RUNTIME_API unsigned int rigbake_runtime_version(void);

/* The last failed call's message on this thread (one line, e.g. "/muscles/3/originNode: must be a node
 * index below 57"); "" when none has failed. Valid until the next call on this thread. */
RIGBAKE_RUNTIME_API const char* rigbake_last_error(void);

typedef struct rigbake_rig rigbake_rig;

/* Builds a rig from the RIGBAKE_muscle_rig extension object: json holds json_size bytes of JSON text,
 * the value of the glTF root's "extensions"."RIGBAKE_muscle_rig" (not the whole glTF document), need
 * not be zero-terminated, and may be freed after the call. node_count is the file's node count
 * (length of its "nodes" array); every node index in the extension must be below it. The text is read
 * strictly (RFC 8259, at most 64 levels deep, 256 MiB) and checked as rigbake validate checks it
 * (version 1, every member's type and size, node indices, 0 < compression <= 1 <= stretch, rest
 * lengths > 0, keys ascending, jiggle axes unit and perpendicular, settings in range), except that a
 * node is a joint of a skin, which the extension cannot tell. Numbers are read in double and the rig
 * is evaluated in float.
 * Returns the rig (owned by the caller, freed by rigbake_rig_destroy), with every jiggle not started
 * (its first rigbake_jiggle_step starts it at rest); or NULL, with rigbake_last_error() saying why. */
RIGBAKE_RUNTIME_API rigbake_rig* rigbake_rig_create(const char* json, size_t json_size, int node_count);

/* Frees a rig; NULL is allowed. */
RIGBAKE_RUNTIME_API void rigbake_rig_destroy(rigbake_rig* rig);

/* Sizes and names. Each returns -1 (or NULL for a name) for a null rig or an index out of range.
 * Names are the extension's, zero-terminated UTF-8, owned by the rig. */
RIGBAKE_RUNTIME_API int rigbake_rig_node_count(const rigbake_rig* rig);
RIGBAKE_RUNTIME_API int rigbake_rig_muscle_count(const rigbake_rig* rig);
RIGBAKE_RUNTIME_API int rigbake_rig_jiggle_count(const rigbake_rig* rig);
RIGBAKE_RUNTIME_API const char* rigbake_rig_muscle_name(const rigbake_rig* rig, int muscle);
/* 1 for a corrective (the extension's "kind": "corrective"), 0 for a muscle. */
RIGBAKE_RUNTIME_API int rigbake_rig_muscle_is_corrective(const rigbake_rig* rig, int muscle);
/* which: 0 skinned, 1 origin, 2 insertion, 3 carrier, 4 base helper, 5 tip helper, 6 driver helper
 * (-1 for a helper when the file has none). */
RIGBAKE_RUNTIME_API int rigbake_rig_muscle_node(const rigbake_rig* rig, int muscle, int which);
RIGBAKE_RUNTIME_API const char* rigbake_rig_jiggle_name(const rigbake_rig* rig, int jiggle);
/* which: 0 the jiggling node, 1 its parent (-1: model space), 2 its root (-1: model space). */
RIGBAKE_RUNTIME_API int rigbake_rig_jiggle_node(const rigbake_rig* rig, int jiggle, int which);
/* 1 when some muscle or jiggle reads node's matrix, 0 when not, -1 for a null rig or node out of range. */
RIGBAKE_RUNTIME_API int rigbake_rig_node_used(const rigbake_rig* rig, int node);

/* Evaluates every muscle for one pose (the extension's equations 1-9).
 * node_matrices: node_count * 16 floats, the pose's world matrices (only the origin, insertion and
 *   carrier nodes are read).
 * skinned_matrices (out): muscle_count * 16 floats, each muscle's skinned-node world matrix M (equation
 *   8); its local matrix is the carrier's inverse world times it, and glTF skinning uses
 *   M * inverseBindMatrix as with any joint.
 * helper_matrices (out, optional, NULL to skip): muscle_count * 48 floats, per muscle the world
 *   matrices of the helpers base, tip and driver (equation 9), whether or not the file has helper nodes.
 * drivers (out, optional, NULL to skip): muscle_count * 3 floats, per muscle its length ratio, the ratio
 *   clamped to [compression, stretch], and its twist (radians, in (-pi, pi]).
 * Arrays must not overlap. Costs about 40 ns per muscle (docs/runtime.md, bench/run). */
RIGBAKE_RUNTIME_API int rigbake_rig_evaluate(const rigbake_rig* rig, const float* node_matrices, float* skinned_matrices,
                                             float* helper_matrices, float* drivers);

/* Copies each muscle's matrix from skinned_matrices (muscle_count * 16 floats, as rigbake_rig_evaluate
 * wrote them) into node_matrices (node_count * 16 floats, in and out) at its skinned node: the pose the
 * jiggles read, for jiggles that ride a muscle's skinned node. */
RIGBAKE_RUNTIME_API int rigbake_rig_store_skinned(const rigbake_rig* rig, const float* skinned_matrices, float* node_matrices);

/* Starts every jiggle at rest on its target (JiggleResetJob): the jiggle point on its animated place,
 * moving with it when velocity_matrices is given. Impulses given since the last step act at the reset.
 * node_matrices: node_count * 16 floats, the animated (not jiggled) pose, with the muscles' skinned
 *   nodes already evaluated (rigbake_rig_store_skinned) when jiggles ride them.
 * velocity_matrices (optional, NULL: the jiggles start still): the same nodes at another time, and
 *   velocity_time that time relative to node_matrices' in seconds (non-zero, negative for an earlier
 *   frame); the jiggle points start with their targets' velocity. */
RIGBAKE_RUNTIME_API int rigbake_jiggle_reset(rigbake_rig* rig, const float* node_matrices, const float* velocity_matrices,
                                             float velocity_time);

/* Advances every jiggle to this frame (JiggleJob): steps of 1/240 s that fall in delta_time plus the
 * time left over from earlier frames, each against its target interpolated between the last frame's
 * pose and this one, then the outputs for this frame. A jiggle that has not started is started at rest
 * on this frame (no step).
 * node_matrices: node_count * 16 floats, this frame's animated (not jiggled) pose, muscles evaluated as
 *   for rigbake_jiggle_reset.
 * delta_time: seconds since the last step or reset, >= 0 and finite.
 * max_steps: steps a frame may take at most (a hitch drops the rest of its time); 0 for no limit.
 * Outputs, each optional (NULL to skip), per jiggle:
 *   corrections: jiggle_count * 4 floats, the rotation to multiply onto the jiggling node's animated
 *     local rotation (local = animated local * correction); exactly (0, 0, 0, 1) at rest;
 *   local_rotations: jiggle_count * 4 floats, the jiggled rotation relative to the parent node;
 *   model_matrices: jiggle_count * 16 floats, the jiggling node's world matrix with the jiggle;
 *   points: jiggle_count * 3 floats, the jiggle point after the cone clamp, world space.
 * The state the steps integrate is double (JiggleState), whatever the float matrices. */
RIGBAKE_RUNTIME_API int rigbake_jiggle_step(rigbake_rig* rig, const float* node_matrices, float delta_time, int max_steps,
                                            float* corrections, float* local_rotations, float* model_matrices, float* points);

/* A hit ("Combat Reaction"): adds magnitude * direction / |direction| (world space, units per second)
 * to the velocity of jiggle `jiggle` (or of every jiggle when jiggle is -1) at its next step, or at the
 * next reset when one comes first. direction: 3 floats, non-zero and finite. */
RIGBAKE_RUNTIME_API int rigbake_jiggle_impulse(rigbake_rig* rig, int jiggle, const float* direction, float magnitude);

#ifdef __cplusplus
}
#endif

#endif /* RIGBAKE_RUNTIME_H */
