# Runs voxfuse_viewer under a virtual X server with Mesa's software renderer on the default data,
# lets it save a screenshot after a few frames, and checks that the panels show images.
# Variables: VIEWER, CHECKER, XVFB_RUN, WORK_DIR, FRAMES (default 15).

foreach(var VIEWER CHECKER XVFB_RUN WORK_DIR)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "RunViewerScreenshot.cmake needs -D${var}=...")
  endif()
endforeach()
if(NOT DEFINED FRAMES)
  set(FRAMES 15)
endif()

file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")
set(shot "${WORK_DIR}/shot.png")

# No GPU needed (and none used by accident): Mesa renders in software.
set(ENV{LIBGL_ALWAYS_SOFTWARE} 1)
execute_process(
  COMMAND "${XVFB_RUN}" -a -s "-screen 0 1280x800x24" "${VIEWER}" --frames ${FRAMES} --screenshot "${shot}" --exit
  WORKING_DIRECTORY "${WORK_DIR}"
  RESULT_VARIABLE viewer_rc
  OUTPUT_VARIABLE viewer_out
  ERROR_VARIABLE viewer_out)
message(STATUS "voxfuse_viewer output:\n${viewer_out}")
if(NOT viewer_rc EQUAL 0)
  message(FATAL_ERROR "voxfuse_viewer exited with ${viewer_rc}")
endif()
if(NOT EXISTS "${shot}")
  message(FATAL_ERROR "voxfuse_viewer did not write ${shot}")
endif()

execute_process(COMMAND "${CHECKER}" "${shot}" RESULT_VARIABLE check_rc OUTPUT_VARIABLE check_out ERROR_VARIABLE check_out)
message(STATUS "${check_out}")
if(NOT check_rc EQUAL 0)
  message(FATAL_ERROR "the screenshot ${shot} failed the check")
endif()

# The viewer takes voxfuse's source, map and tracker options (app::PipelineOptions): a synthetic
# source, frames skipped, another tracker and a depth limit.
set(shot2 "${WORK_DIR}/shot_options.png")
execute_process(
  COMMAND "${XVFB_RUN}" -a -s "-screen 0 1280x800x24" "${VIEWER}" synthetic:6 --skip 2 --tracker rgbd --max-depth 2.5 --frames 3
          --screenshot "${shot2}" --exit
  WORKING_DIRECTORY "${WORK_DIR}"
  RESULT_VARIABLE viewer_rc
  OUTPUT_VARIABLE viewer_out
  ERROR_VARIABLE viewer_out)
if(NOT viewer_rc EQUAL 0 OR NOT EXISTS "${shot2}")
  message(FATAL_ERROR "voxfuse_viewer with the pipeline options exited with ${viewer_rc}:\n${viewer_out}")
endif()
if(NOT viewer_out MATCHES "synthetic room" OR NOT viewer_out MATCHES "skipped the first 2 frames")
  message(FATAL_ERROR "voxfuse_viewer did not read the synthetic source after skipping 2 frames:\n${viewer_out}")
endif()
execute_process(COMMAND "${CHECKER}" "${shot2}" RESULT_VARIABLE check_rc OUTPUT_VARIABLE check_out ERROR_VARIABLE check_out)
if(NOT check_rc EQUAL 0)
  message(FATAL_ERROR "the screenshot ${shot2} failed the check:\n${check_out}")
endif()
# And refuses what voxfuse refuses, before any window opens.
execute_process(COMMAND "${VIEWER}" --device-uri some-camera WORKING_DIRECTORY "${WORK_DIR}" RESULT_VARIABLE viewer_rc ERROR_VARIABLE viewer_err)
if(viewer_rc EQUAL 0 OR NOT viewer_err MATCHES "needs --live")
  message(FATAL_ERROR "voxfuse_viewer --device-uri without --live must be refused; got ${viewer_rc}: ${viewer_err}")
endif()
