# Hostile input (issue 12): malformed scene files, PLYs, images and binary data, each refused with
# one stderr line naming the file and the element, a non-zero exit and no image (the same check as
# PRISM_BAD_INPUTS, which this extends). Each file differs from tests/data/good.xml or good.json
# (both render: cli/good_*) only by its fault.
list(APPEND PRISM_BAD_INPUTS
  "recursion_depth_over_limit.xml|recursion_depth_over_limit.xml|MaxRecursionDepth"
  "recursion_depth_negative.xml|recursion_depth_negative.xml|MaxRecursionDepth"
  "recursion_depth_twice.xml|recursion_depth_twice.xml|MaxRecursionDepth"
  "resolution_over_limit.xml|resolution_over_limit.xml|ImageResolution"
  "resolution_pixels_over_limit.xml|resolution_pixels_over_limit.xml|ImageResolution"
  "resolution_int_overflow.xml|resolution_int_overflow.xml|ImageResolution"
  "resolution_one_number.xml|resolution_one_number.xml|ImageResolution"
  "resolution_zero.xml|resolution_zero.xml|ImageResolution"
  "samples_over_limit.xml|samples_over_limit.xml|NumSamples"
  "samples_zero.xml|samples_zero.xml|NumSamples"
  "samples_not_a_number.xml|samples_not_a_number.xml|NumSamples"
  "elements_nested_too_deep.xml|elements_nested_too_deep.xml|nest"
  "instance_cycle.xml|instance_cycle.xml|MeshInstance"
  "instance_unknown_base.xml|instance_unknown_base.xml|MeshInstance"
  "image_name_absolute.xml|image_name_absolute.xml|ImageName"
  "image_name_parent.xml|image_name_parent.xml|ImageName"
  "image_name_climbs_out.xml|image_name_climbs_out.xml|ImageName"
  "image_name_no_file.xml|image_name_no_file.xml|ImageName"
  "image_name_empty.xml|image_name_empty.xml|ImageName"
  "image_name_missing.xml|image_name_missing.xml|ImageName"
  "image_name_format.xml|image_name_format.xml|ImageName>: \"out.bmp\": unsupported output format"
  "camera_unknown_type.xml|camera_unknown_type.xml|Camera"
  "near_plane_three_numbers.xml|near_plane_three_numbers.xml|NearPlane"
  "near_plane_no_area.xml|near_plane_no_area.xml|NearPlane"
  "near_distance_zero.xml|near_distance_zero.xml|Camera"
  "fovy_out_of_range.xml|fovy_out_of_range.xml|FovY"
  "position_not_numbers.xml|position_not_numbers.xml|Position"
  "no_camera.xml|no_camera.xml|Cameras"
  "root_not_scene.xml|root_not_scene.xml|Scenery"
  "empty_file.xml|empty_file.xml|line"
  "mismatched_tags.xml|mismatched_tags.xml|Camera"
  "unclosed_attribute.xml|unclosed_attribute.xml|Objects"
  "faces_not_triangles.xml|faces_not_triangles.xml|Faces"
  "faces_index_zero.xml|faces_index_zero.xml|Faces"
  "faces_vertex_offset_out_of_range.xml|faces_vertex_offset_out_of_range.xml|Faces"
  "faces_missing.xml|faces_missing.xml|Mesh"
  "vertex_data_not_triples.xml|vertex_data_not_triples.xml|VertexData"
  "vertex_data_binary_missing.xml|vertex_data_binary_missing.xml|VertexData"
  "vertex_data_binary_truncated.xml|vertex_data_binary_truncated.xml|VertexData"
  "vertex_data_binary_device.xml|/dev/zero: vertex data: not a regular file|VertexData"
  "ply_device.xml|/dev/zero: not a regular file|Faces"
  "scene_device.xml|scene_device.xml: not a regular file|not a regular file"
  "scene_device.json|scene_device.json: not a regular file|not a regular file"
  "sphere_negative_radius.xml|sphere_negative_radius.xml|Radius"
  "sphere_unknown_center.xml|sphere_unknown_center.xml|Center"
  "plane_zero_normal.xml|plane_zero_normal.xml|Normal"
  "triangle_two_indices.xml|triangle_two_indices.xml|Indices"
  "unknown_transformation.xml|unknown_transformation.xml|Transformations"
  "shading_mode_unknown.xml|shading_mode_unknown.xml|Mesh"
  "material_not_a_number.xml|material_not_a_number.xml|PhongExponent"
  "material_unknown_type.xml|material_unknown_type.xml|Material"
  "ply_bad_magic.xml|not_a_ply.ply|header line 1"
  "ply_huge_count.xml|ply_huge_count.ply|vertex"
  "ply_unknown_format.xml|ply_unknown_format.ply|header line 2"
  "ply_no_end_header.xml|ply_no_end_header.ply|header line"
  "ply_face_out_of_range.xml|ply_face_out_of_range.ply|Faces"
  "ply_ascii_garbage.xml|ply_ascii_garbage.ply|vertex"
  "ply_is_a_folder.xml|bad: is a directory|Faces"
  "texture_garbage_png.xml|garbage.png|Image"
  "texture_huge_png.xml|huge.png|Image"
  "texture_broken_exr.xml|broken_chunk.exr|Image"
  "texture_unsupported_format.xml|image.gif|Image"
  "json_nested_too_deep.json|json_nested_too_deep.json|nest"
  "json_top_level_array.json|json_top_level_array.json|JSON object"
  "json_truncated.json|json_truncated.json|line"
  "json_attribute_object.json|json_attribute_object.json|attribute"
  "json_resolution_over_limit.json|json_resolution_over_limit.json|ImageResolution"
  "json_image_name_absolute.json|json_image_name_absolute.json|ImageName"
  "json_recursion_depth_over_limit.json|json_recursion_depth_over_limit.json|MaxRecursionDepth"
  "json_two_roots.json|json_two_roots.json|root"
)
# The unit tests of test_hostile_input.cpp read tests/data (good.xml, the fuzzers' findings). A
# definition for the whole target, not for that file: a file with definitions of its own is left
# out of its unity group (tests/CMakeLists.txt).
target_compile_definitions(prism_tests PRIVATE PRISM_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
add_test(NAME cli/good_json_scene_renders
         COMMAND prism-render ${CMAKE_CURRENT_SOURCE_DIR}/data/good.json --output-dir ${CMAKE_CURRENT_BINARY_DIR}/good_json_output)
# The rows of issue 12's table (facing mirrors asking for 10^8 bounces, 200,000 nested elements,
# huge resolution and sample counts, names outside --output-dir) and Ctrl-C.
foreach(row IN ITEMS mirror_room_depth nested_xml nested_json resolution samples absolute_name parent_name interrupt)
  add_test(NAME hostile/${row}
           COMMAND bash ${CMAKE_CURRENT_SOURCE_DIR}/check_issue_rows.sh ${row} $<TARGET_FILE:prism-render>
                   ${CMAKE_CURRENT_BINARY_DIR}/hostile/${row} ${CMAKE_CURRENT_SOURCE_DIR}/data/good.xml ${PRISM_SHARED_DIR})
  set_tests_properties(hostile/${row} PROPERTIES SKIP_REGULAR_EXPRESSION "skipped:")
endforeach()
