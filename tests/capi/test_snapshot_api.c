/* Scene snapshots and tile-range bakes through the C ABI, from C: a loaded
 * scene bakes the bits of the scene saved; tile ranges put together give the
 * whole bake's bits; bad files give errors naming the problem. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "omis/omis.h"

#include "check.h"
#include "floor_scene.h"

enum { W = 40, H = 24 };

static OMISBake lightmap_job(OMISScene scene, int first_tile, int tile_count) {
    OMISBake bake = omisNewBake(scene, OMIS_BAKE_LIGHTMAP, 0);
    omisSetBakeInt(bake, "width", W);
    omisSetBakeInt(bake, "height", H);
    omisSetBakeInt(bake, "samples", 8);
    omisSetBakeInt(bake, "seed", 7);
    omisSetBakeInt(bake, "margin", 4);
    if (tile_count > 0) {
        omisSetBakeInt(bake, "firstTile", first_tile);
        omisSetBakeInt(bake, "tileCount", tile_count);
    }
    omisCommitBake(bake);
    return bake;
}

/* The baked value of a scene, copied (W·H·3 floats; the caller frees it). */
static float* bake_values(OMISScene scene) {
    OMISBake bake = lightmap_job(scene, 0, 0);
    OMISBakeResult result = omisExecuteBake(bake);
    float* copy = malloc(sizeof(float) * W * H * 3);
    CHECK(result != NULL);
    if (result) memcpy(copy, omisGetBakeResultData(result, "value"), sizeof(float) * W * H * 3);
    omisReleaseBakeResult(result);
    omisReleaseBake(bake);
    return copy;
}

static void check_round_trip(OMISScene scene, const float* expected) {
    const char* path = "snapshot_api_test.omis";
    OMISScene loaded;
    float* value;
    CHECK(omisSaveScene(scene, path));
    loaded = omisLoadScene(path);
    CHECK(loaded != NULL);
    CHECK(omisFindMesh(loaded, "floor") == 0);
    value = bake_values(loaded); /* loaded scenes are committed */
    CHECK(memcmp(value, expected, sizeof(float) * W * H * 3) == 0);
    free(value);
    omisReleaseScene(loaded);
    remove(path);
}

/* Three tile ranges put together, against the whole bake. */
static void check_tile_ranges(OMISScene scene, const float* expected) {
    static float value[W * H * 3], noise[W * H], mask[W * H];
    OMISBake whole = lightmap_job(scene, 0, 0);
    const size_t tiles = omisGetBakeTileCount(whole);
    const int ranges[3][2] = {{0, 2}, {2, 1}, {3, 3}};
    OMISBakeResult composed;
    int r, i, c;
    CHECK(tiles == 6); /* 40×24 texels: 3 × 2 tiles of 16² */
    for (r = 0; r < 3; ++r) {
        OMISBake part = lightmap_job(scene, ranges[r][0], ranges[r][1]);
        OMISBakeResult result = omisExecuteBake(part);
        const float* v = omisGetBakeResultData(result, "value");
        const float* n = omisGetBakeResultData(result, "noise");
        const float* m = omisGetBakeResultData(result, "mask");
        for (i = 0; i < W * H; ++i) {
            if (m[i] == 0) continue;
            for (c = 0; c < 3; ++c) value[3 * i + c] = v[3 * i + c];
            noise[i] = n[i];
            mask[i] = 1;
        }
        omisReleaseBakeResult(result);
        omisReleaseBake(part);
    }
    composed = omisComposeBakeResult(whole, value, noise, mask);
    CHECK(composed != NULL);
    CHECK(memcmp(omisGetBakeResultData(composed, "value"), expected, sizeof value) == 0);
    omisReleaseBakeResult(composed);
    omisReleaseBake(whole);
    /* a range outside the tiles is refused at commit */
    whole = lightmap_job(scene, 5, 2);
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "tiles"));
    omisReleaseBake(whole);
}

static void check_bad_files(OMISScene scene) {
    const size_t size = omisSaveSceneToMemory(scene, NULL, 0);
    unsigned char* bytes = malloc(size);
    CHECK(size > 64 && omisSaveSceneToMemory(scene, bytes, size) == size);
    CHECK(omisLoadSceneFromMemory(bytes, size / 2) == NULL);
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "truncated"));
    bytes[size - 9] ^= 0x10; /* inside the last section */
    CHECK(omisLoadSceneFromMemory(bytes, size) == NULL);
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "checksum"));
    bytes[size - 9] ^= 0x10;
    bytes[8] = 99; /* format version */
    CHECK(omisLoadSceneFromMemory(bytes, size) == NULL);
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "version 99"));
    CHECK(omisLoadScene("no/such/snapshot.omis") == NULL);
    CHECK(error_is(OMIS_ERROR_UNKNOWN, "cannot open"));
    free(bytes);
}

int main(void) {
    OMISScene scene = floor_scene(1);
    float* expected;
    omisSetMeshName(scene, 0, "floor");
    omisCommitScene(scene);
    CHECK(omisGetError(NULL) == OMIS_ERROR_NONE);
    expected = bake_values(scene);
    check_round_trip(scene, expected);
    check_tile_ranges(scene, expected);
    check_bad_files(scene);
    CHECK(omisFindMesh(scene, "nothing") == OMIS_INVALID_ID);
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "nothing"));
    free(expected);
    omisReleaseScene(scene);
    return check_summary();
}
