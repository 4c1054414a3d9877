/* The C tests' scene: a 2 m floor (two triangles, optional UVs over [0,1]²)
 * under a 1 m rect light facing down; not yet committed. */
#ifndef OMIS_TESTS_FLOOR_SCENE_H
#define OMIS_TESTS_FLOOR_SCENE_H

#include <stddef.h>

#include "omis/omis.h"

static OMISScene floor_scene(int with_uvs) {
    const float vertices[] = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0};
    const uint32_t triangles[] = {0, 1, 2, 0, 2, 3};
    const float uvs[] = {0, 0, 1, 0, 1, 1, 0, 0, 1, 1, 0, 1};
    const double corner[3] = {-0.5, -0.5, 1}, u[3] = {0, 1, 0}, v[3] = {1, 0, 0};
    const double radiance[3] = {1, 1, 1};
    OMISScene scene = omisNewScene();
    omisAddMesh(scene, vertices, OMIS_DATA_FLOAT32, 0, 4, triangles, 2, NULL,
                     with_uvs ? uvs : NULL, NULL);
    omisAddRectLight(scene, corner, u, v, radiance, false, 3.14159265358979);
    return scene;
}

#endif
