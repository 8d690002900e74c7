# Label fusion from the command line on the bundled data: a semantic voxel type finds labels.txt beside
# the sequence, the summary counts the labelled frames, the mesh carries a label property, class renders
# are written, and --exclude-classes removes a class from the mesh and from the per-class meshes.
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})
set(out_dir ${WORK_DIR}/out)
execute_process(COMMAND ${VOXFUSE_CLI} --voxel s_rgb_label --frames 8 --render-every 0 --mesh --mesh-per-class --exclude-classes 1
                        --cloud --out ${out_dir}
                WORKING_DIRECTORY ${WORK_DIR} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "voxfuse --voxel s_rgb_label failed (${rc}):\n${out}\n${err}")
endif()
message(STATUS "${out}\n${err}")

file(READ ${out_dir}/summary.json summary)
string(JSON with_labels GET "${summary}" frames_with_labels)
if(NOT with_labels EQUAL 8)
  message(FATAL_ERROR "expected 8 frames with labels in summary.json, got ${with_labels}")
endif()
file(GLOB class_renders ${out_dir}/render_class_*.png)
if(NOT class_renders)
  message(FATAL_ERROR "no render_class_*.png was written")
endif()

# Binary PLY: the header is text up to end_header.
file(READ ${out_dir}/mesh.ply header LIMIT 400)
if(NOT header MATCHES "property ushort label")
  message(FATAL_ERROR "mesh.ply has no label property:\n${header}")
endif()
file(READ ${out_dir}/cloud.ply header LIMIT 400)
if(NOT header MATCHES "property ushort label")
  message(FATAL_ERROR "cloud.ply has no label property:\n${header}")
endif()
if(EXISTS ${out_dir}/mesh_class_1.ply)
  message(FATAL_ERROR "class 1 (floor) was excluded but mesh_class_1.ply was written")
endif()
foreach(class 2 4)  # wall and table are in view from the first frames
  if(NOT EXISTS ${out_dir}/mesh_class_${class}.ply)
    message(FATAL_ERROR "mesh_class_${class}.ply was not written")
  endif()
endforeach()

# Labels with a voxel type that cannot store them are refused, not silently dropped.
execute_process(COMMAND ${VOXFUSE_CLI} --voxel s --labels ${DATA_DIR}/labels.txt --frames 1 --out ${WORK_DIR}/refused
                WORKING_DIRECTORY ${WORK_DIR} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(rc EQUAL 0 OR NOT err MATCHES "voxel type with classes")
  message(FATAL_ERROR "--labels with --voxel s must fail with a reason; got ${rc}: ${err}")
endif()

# Class outputs asked of a voxel type without classes are refused before the run, not after it.
execute_process(COMMAND ${VOXFUSE_CLI} --voxel s_rgb --mesh-per-class --frames 2 --out ${WORK_DIR}/no_classes
                WORKING_DIRECTORY ${WORK_DIR} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(rc EQUAL 0 OR NOT err MATCHES "need a voxel type with classes" OR EXISTS ${WORK_DIR}/no_classes/trajectory.txt)
  message(FATAL_ERROR "--mesh-per-class with --voxel s_rgb must fail before the run; got ${rc}: ${err}")
endif()
