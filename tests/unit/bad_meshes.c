/* The bad fixtures of every mesh format (tests/data/mesh/bad_*), where each one's error line must
 * point and what it must say, and the test that loads them; see mesh_fixture.h. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <string.h>

#include "mesh_fixture.h"

static const struct {
    const char *name, *location, *message;
} bad_inputs[] = {
    {"bad_number.obj", ":2: ", "bad number 'x'"},
    {"bad_nan.obj", ":1: ", "bad number 'nan'"},
    {"bad_inf.obj", ":3: ", "bad number '1e999'"},
    {"bad_v_few.obj", ":2: ", "found 2 numbers"},
    {"bad_v_many.obj", ":1: ", "too many numbers"},
    {"bad_vn_count.obj", ":4: ", "expected 'vn x y z'"},
    {"bad_index_range.obj", ":4: ", "'4': vertex index out of range (3 defined"},
    {"bad_index_negative.obj", ":4: ", "'-4': vertex index out of range"},
    {"bad_index_zero.obj", ":4: ", "bad face corner '0'"},
    {"bad_index_huge.obj", ":4: ", "vertex index out of range"},
    {"bad_forward_ref.obj", ":1: ", "(0 defined so far)"},
    {"bad_normal_range.obj", ":5: ", "'2//2': normal index out of range"},
    {"bad_texcoord_range.obj", ":5: ", "'3/2': texture coordinate index out of range"},
    {"bad_corner_slash.obj", ":4: ", "bad face corner '1/'"},
    {"bad_corner_fields.obj", ":6: ", "bad face corner '1/1/1/1'"},
    {"bad_corner_text.obj", ":4: ", "bad face corner 'a'"},
    {"bad_face_two.obj", ":4: ", "face with 2 vertices"},
    {"bad_empty.obj", ": ", "no triangles"},
    {"bad_no_faces.obj", ": ", "no triangles"},
    {"bad_all_degenerate.obj", ": ", "no triangles (2 degenerate"},
    {"bad_empty.ply", ": ", "empty file"},
    {"bad_magic.ply", ":1: ", "not a PLY file"},
    {"bad_big_endian.ply", ":2: ", "big-endian binary PLY is not supported"},
    {"bad_format.ply", ":2: ", "unknown PLY format 'binary'"},
    {"bad_version.ply", ":2: ", "unsupported PLY version '2.0'"},
    {"bad_no_format.ply", ":3: ", "no format line"},
    {"bad_no_end_header.ply", ":3: ", "without end_header"},
    {"bad_property_first.ply", ":3: ", "property before any element"},
    {"bad_type.ply", ":4: ", "unknown property type 'float128'"},
    {"bad_keyword.ply", ":3: ", "unknown header keyword 'elemnt'"},
    {"bad_count.ply", ":3: ", "bad element count '-3'"},
    {"bad_count_overflow.ply", ":3: ", "bad element count"},
    {"bad_no_z.ply", ":3: ", "needs x, y and z"},
    {"bad_partial_normals.ply", ":3: ", "nx, ny and nz"},
    {"bad_no_face.ply", ": ", "no 'face' element"},
    {"bad_indices_scalar.ply", ":7: ", "'vertex_indices' must be a list"},
    {"bad_few_values.ply", ":11: ", "too few values for a 'vertex' row"},
    {"bad_many_values.ply", ":11: ", "more values than the header declares"},
    {"bad_few_rows.ply", ":13: ", "'face' declares 2 rows, found 1"},
    {"bad_extra_rows.ply", ":15: ", "data after the last element"},
    {"bad_ply_index_range.ply", ":13: ", "vertex index 3 is not an integer in [0, 3)"},
    {"bad_ply_index_negative.ply", ":13: ", "vertex index -1"},
    {"bad_ply_index_fraction.ply", ":13: ", "vertex index 1.5"},
    {"bad_ply_face_two.ply", ":13: ", "face with 2 vertices"},
    {"bad_ply_list_count.ply", ":13: ", "bad list count -1"},
    {"bad_ply_nan.ply", ":11: ", "not a finite float"},
    {"bad_ply_number.ply", ":11: ", "bad number 'abc'"},
    {"bad_ply_float_range.ply", ":11: ", "not a finite float"},
    {"bad_ply_claims.ply", ":12: ", "'vertex' declares 4000000000 rows, found 3"},
    {"bad_stl_outside.stl", ":3: ", "'vertex' outside 'outer loop'"},
    {"bad_stl_two.stl", ":6: ", "loop with 2 vertices; at least 3 needed"},
    {"bad_stl_keyword.stl", ":6: ", "unknown STL keyword 'vertx'"},
    {"bad_stl_unended.stl", ":6: ", "file ends inside a facet"},
    {"bad_stl_number.stl", ":4: ", "bad number 'nan'"},
    {"bad_stl_size.stl", ": ", "declares 2 triangles (184 bytes) but the file has 134 bytes"},
    {"bad_gltf_json.gltf", ":3: ", "JSON: unexpected character"},
    {"bad_gltf_asset.gltf", ": ", "no asset.version"},
    {"bad_gltf_version.gltf", ": ", "glTF version '1.0'; only 2.x is supported"},
    {"bad_gltf_extension.gltf", ": ", "requires extension 'EXT_mesh_gpu_instancing', which places meshes many times "
                                      "and which aoview does not read"},
    {"bad_gltf_sparse.gltf", ": ", "accessor 0 (POSITION) sparse: no 'indices' and 'values' objects"},
    {"bad_gltf_position_type.gltf", ": ", "componentType 5125; positions and normals must be float (5126), or byte"},
    {"bad_gltf_index_count.gltf", ": ", "2 indices, not a whole number of triangles"},
    {"bad_gltf_mesh_index.gltf", ": ", "node 1: 'mesh' 7 is out of range (2 defined)"},
    {"bad_gltf_uri.gltf", ": ", "buffer 0 ('http://example.com/x.bin'): the URI scheme 'http:' is not supported"},
    {"bad_gltf_base64.gltf", ": ", "buffer 0: bad base64 data"},
};

void test_bad_inputs(void **state)
{
    const char *ext = *state;
    size_t found = 0, n = strlen(ext);
    for (size_t i = 0; i < sizeof bad_inputs / sizeof bad_inputs[0]; i++) {
        const char *name = bad_inputs[i].name;
        if (strlen(name) > n && strcmp(name + strlen(name) - n, ext) == 0) {
            expect_failure(fixture(name), bad_inputs[i].location, bad_inputs[i].message);
            found++;
        }
    }
    assert_true(found > 0);
}
