/* A C program that uses librigbake_runtime.so through runtime/rigbake_runtime.h alone, as an engine
 * written in C (or any FFI) would. tests/runtime_c_api_test.cpp gives it a real bake's extension text and
 * a clip's node matrices and compares what it writes with the C++ runtime's results.
 *
 * usage: runtime_c_check EXTENSION.json NODE_COUNT POSES.f32 FRAME_SECONDS OUT.f32
 * POSES.f32: frames * NODE_COUNT * 16 floats. For every frame it evaluates the muscles, stores them into
 * the pose, steps the jiggles by FRAME_SECONDS (at frame 5 after a hit on every jiggle) and appends to
 * OUT.f32 the muscles' skinned matrices then the jiggles' corrections. It also checks the API's refusals.
 * Exit 0 on success; otherwise it says on stderr what failed. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "runtime/rigbake_runtime.h"

static int failures = 0;

static void check(int condition, const char* what) {
  if (!condition) {
    fprintf(stderr, "runtime_c_check: %s (last error: %s)\n", what, rigbake_last_error());
    ++failures;
  }
}

static char* readAll(const char* path, size_t* size) {
  FILE* file = fopen(path, "rb");
  char* data;
  long length;
  if (!file) return NULL;
  fseek(file, 0, SEEK_END);
  length = ftell(file);
  fseek(file, 0, SEEK_SET);
  data = (char*)malloc(length > 0 ? (size_t)length : 1);
  if (data && fread(data, 1, (size_t)length, file) != (size_t)length) {
    free(data);
    data = NULL;
  }
  fclose(file);
  *size = (size_t)length;
  return data;
}

/* What every caller may get wrong must come back as a code and a message, never a crash. */
static void checkRefusals(const char* json, size_t json_size, int node_count) {
  static const char broken[] = "{\"version\": 1, \"muscles\": [}";
  static const char wrong_version[] = "{\"version\": 2, \"muscles\": []}";
  float direction[3] = {0, 0, 0};
  rigbake_rig* rig;
  check(rigbake_rig_create(broken, sizeof(broken) - 1, node_count) == NULL, "malformed JSON was accepted");
  check(strstr(rigbake_last_error(), "JSON syntax at byte") != NULL, "malformed JSON: no byte offset in the message");
  check(rigbake_rig_create(wrong_version, sizeof(wrong_version) - 1, node_count) == NULL, "version 2 was accepted");
  check(strstr(rigbake_last_error(), "/version") != NULL, "version 2: the message does not name /version");
  check(rigbake_rig_create(json, json_size, 1) == NULL, "a node count below the rig's nodes was accepted");
  check(strstr(rigbake_last_error(), "must be a node index below 1") != NULL, "node count: the message does not say why");
  check(rigbake_rig_create(json, json_size / 2, node_count) == NULL, "half of the extension text was accepted");
  rig = rigbake_rig_create(json, json_size, node_count);
  check(rig != NULL, "the extension text was refused");
  if (!rig) return;
  check(rigbake_rig_evaluate(rig, NULL, NULL, NULL, NULL) == RIGBAKE_ERROR_ARGUMENT, "evaluate accepted null arrays");
  check(rigbake_jiggle_step(rig, NULL, 0.1f, 0, NULL, NULL, NULL, NULL) == RIGBAKE_ERROR_ARGUMENT, "step accepted a null pose");
  check(rigbake_jiggle_impulse(rig, 0, direction, 1.0f) == RIGBAKE_ERROR_ARGUMENT, "impulse accepted a zero direction");
  check(rigbake_jiggle_impulse(rig, rigbake_rig_jiggle_count(rig), direction, 1.0f) == RIGBAKE_ERROR_ARGUMENT,
        "impulse accepted a jiggle out of range");
  check(rigbake_rig_muscle_name(rig, -1) == NULL && rigbake_rig_muscle_node(rig, 0, 7) == -1, "an index out of range answered");
  rigbake_rig_destroy(rig);
  rigbake_rig_destroy(NULL);
}

int main(int argc, char** argv) {
  size_t json_size = 0, poses_size = 0;
  char *json, *poses_bytes;
  int node_count, muscles, jiggles, frame, frames;
  float frame_seconds;
  float *skinned, *corrections, *pose;
  float hit[3] = {0.0f, 0.0f, 1.0f};
  rigbake_rig* rig;
  FILE* out;
  if (argc != 6) {
    fprintf(stderr, "usage: runtime_c_check EXTENSION.json NODE_COUNT POSES.f32 FRAME_SECONDS OUT.f32\n");
    return 1;
  }
  check(rigbake_runtime_version() == RIGBAKE_RUNTIME_VERSION, "the library's version is not the header's");
  json = readAll(argv[1], &json_size);
  node_count = atoi(argv[2]);
  poses_bytes = readAll(argv[3], &poses_size);
  frame_seconds = (float)atof(argv[4]);
  if (!json || !poses_bytes || node_count <= 0) {
    fprintf(stderr, "runtime_c_check: cannot read the inputs\n");
    return 1;
  }
  checkRefusals(json, json_size, node_count);
  rig = rigbake_rig_create(json, json_size, node_count);
  if (!rig) {
    fprintf(stderr, "runtime_c_check: %s\n", rigbake_last_error());
    return 1;
  }
  muscles = rigbake_rig_muscle_count(rig);
  jiggles = rigbake_rig_jiggle_count(rig);
  frames = (int)(poses_size / (sizeof(float) * 16 * (size_t)node_count));
  skinned = (float*)malloc(sizeof(float) * 16 * (size_t)(muscles > 0 ? muscles : 1));
  corrections = (float*)malloc(sizeof(float) * 4 * (size_t)(jiggles > 0 ? jiggles : 1));
  pose = (float*)malloc(sizeof(float) * 16 * (size_t)node_count);
  out = fopen(argv[5], "wb");
  if (!skinned || !corrections || !pose || !out) return 1;
  for (frame = 0; frame < frames; ++frame) {
    memcpy(pose, poses_bytes + sizeof(float) * 16 * (size_t)node_count * (size_t)frame, sizeof(float) * 16 * (size_t)node_count);
    check(rigbake_rig_evaluate(rig, pose, skinned, NULL, NULL) == RIGBAKE_OK, "evaluate failed");
    check(rigbake_rig_store_skinned(rig, skinned, pose) == RIGBAKE_OK, "store_skinned failed");
    if (frame == 5 && jiggles > 0) check(rigbake_jiggle_impulse(rig, -1, hit, 2.0f) == RIGBAKE_OK, "impulse failed");
    check(rigbake_jiggle_step(rig, pose, frame == 0 ? 0.0f : frame_seconds, 0, corrections, NULL, NULL, NULL) == RIGBAKE_OK,
          "step failed");
    fwrite(skinned, sizeof(float), 16 * (size_t)muscles, out);
    fwrite(corrections, sizeof(float), 4 * (size_t)jiggles, out);
  }
  fclose(out);
  rigbake_rig_destroy(rig);
  free(json);
  free(poses_bytes);
  free(skinned);
  free(corrections);
  free(pose);
  if (failures == 0) printf("runtime_c_check: %d frames, %d muscles, %d jiggles\n", frames, muscles, jiggles);
  return failures == 0 ? 0 : 1;
}
