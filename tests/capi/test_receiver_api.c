/* Receiver closures through the C ABI: omisSetMeshReceiver's errors and its
 * effect on a vertex bake under a delta sun (exact values). */
#include <math.h>
#include <string.h>

#include "omis/omis.h"

#include "check.h"

#define PI 3.14159265358979323846

int main(void) {
    const float vertices[] = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0};
    const uint32_t triangles[] = {0, 1, 2, 0, 2, 3};
    const double theta = 70 * PI / 180;
    const double travel[3] = {-sin(theta), 0, -cos(theta)}, irradiance[3] = {2, 2, 2};
    const char* message = NULL;
    const double c = cos(theta), f = pow(1 - c, 5);
    /* Cycles 3.4 viewed along the normal: principled ratio 1 − F/2 + r(1 + c)F,
     * Oren–Nayar A = 1/(π + (3π − 4)/6 σ) times cosθ. */
    const double expected[3] = {2 * c / PI, 2 * c / PI * (1 - 0.5 * f + 0.5 * (1 + c) * f),
                                2 * c / (PI + (3 * PI - 4) / 6 * 0.8)};
    unsigned int mesh[3];
    int m, i;
    OMISScene scene = omisNewScene();
    for (m = 0; m < 3; ++m)
        mesh[m] = omisAddMesh(scene, vertices, OMIS_DATA_FLOAT32, 0, 4, triangles, 2,
                                   NULL, NULL, NULL);
    omisAddSunLight(scene, travel, irradiance, 0);

    omisSetMeshReceiver(NULL, 0, OMIS_RECEIVER_LAMBERT, 0);
    CHECK(omisGetError(&message) == OMIS_ERROR_INVALID_ARGUMENT && strstr(message, "scene"));
    omisSetMeshReceiver(scene, 9, OMIS_RECEIVER_OREN_NAYAR, 0.5);
    CHECK(omisGetError(&message) == OMIS_ERROR_INVALID_ARGUMENT && strstr(message, "mesh"));
    omisSetMeshReceiver(scene, mesh[1], OMIS_RECEIVER_PRINCIPLED_DIFFUSE, -0.5);
    CHECK(omisGetError(&message) == OMIS_ERROR_INVALID_ARGUMENT && strstr(message, "roughness"));
    omisSetMeshReceiver(scene, mesh[1], (OMISReceiver)7, 0.5);
    CHECK(omisGetError(&message) == OMIS_ERROR_INVALID_ARGUMENT && strstr(message, "receiver"));

    omisSetMeshReceiver(scene, mesh[1], OMIS_RECEIVER_PRINCIPLED_DIFFUSE, 0.5);
    omisSetMeshReceiver(scene, mesh[2], OMIS_RECEIVER_OREN_NAYAR, 0.8);
    CHECK(omisGetError(NULL) == OMIS_ERROR_NONE);
    omisCommitScene(scene);
    omisSetMeshReceiver(scene, mesh[2], OMIS_RECEIVER_LAMBERT, 0);
    CHECK(omisGetError(&message) == OMIS_ERROR_INVALID_OPERATION);

    for (m = 0; m < 3; ++m) {
        OMISBake bake = omisNewBake(scene, OMIS_BAKE_VERTICES, mesh[m]);
        OMISBakeResult result;
        const float* value;
        int width = 0, height = 0;
        omisSetBakeString(bake, "techniques", "bsdf");
        omisSetBakeInt(bake, "samples", 1);
        omisCommitBake(bake);
        result = omisExecuteBake(bake);
        CHECK(result != NULL);
        CHECK(omisGetBakeResultSize(result, &width, &height) && width == 4 && height == 1);
        value = omisGetBakeResultData(result, "value");
        for (i = 0; value && i < 4; ++i) CHECK(fabs(value[3 * i] - expected[m]) < 1e-6);
        omisReleaseBakeResult(result);
        omisReleaseBake(bake);
    }
    omisReleaseScene(scene);
    return check_summary();
}
