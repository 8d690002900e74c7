# voxfuse_bench's map-output benchmark runs and reports every number it promises (not their values:
# timings belong to benchmarks, not to tests).
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})
set(json ${WORK_DIR}/bench.json)
execute_process(COMMAND ${VOXFUSE_BENCH} ${DATA_DIR} --frames 6 --warmup 1 --poses groundtruth --mesh --cloud-voxel 0.02
                        --occupancy 0.1 --repeats 1 --json ${json}
                WORKING_DIRECTORY ${WORK_DIR} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "voxfuse_bench failed (${rc}):\n${out}\n${err}")
endif()
message(STATUS "${out}")
file(READ ${json} report)
foreach(key "meshing;median_ms" "meshing;triangles" "meshing;mesh_mb" "point_cloud;points" "point_cloud;downsampled_points"
            "occupancy;frames_inserted" "occupancy;worker_fps")
  string(JSON value ERROR_VARIABLE json_error GET "${report}" ${key})
  if(json_error)
    message(FATAL_ERROR "bench.json lacks '${key}': ${json_error}")
  endif()
endforeach()
string(JSON triangles GET "${report}" meshing triangles)
string(JSON inserted GET "${report}" occupancy frames_inserted)
string(JSON dropped GET "${report}" occupancy frames_dropped)
math(EXPR accounted "${inserted} + ${dropped}")
if(triangles LESS 10000 OR NOT accounted EQUAL 6)
  message(FATAL_ERROR "expected a mesh and 6 frames inserted or dropped by the occupancy map; got ${triangles} triangles, "
                      "${inserted} inserted + ${dropped} dropped")
endif()
