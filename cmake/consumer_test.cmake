# ctest driver: install the build tree into a temporary prefix, then configure, build and run
# tests/consumer against it; a second build must find nothing to do, and editing the texture the scene
# references must rebake. Arguments: BUILD_DIR SOURCE_DIR WORK_DIR GENERATOR.
file(REMOVE_RECURSE "${WORK_DIR}")
set(prefix "${WORK_DIR}/prefix")
set(build "${WORK_DIR}/build")

function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGN}\n${out}\n${err}")
  endif()
  set(last_output "${out}${err}" PARENT_SCOPE)
endfunction()

run(${CMAKE_COMMAND} --install "${BUILD_DIR}" --prefix "${prefix}")

# `specbake view` serves the installed plugin and viewer, and the three.js files installed beside them when
# the source tree had the pinned copy (tests/consumers/node_modules).
set(web_files share/specbake/web/three/specbake-three.js share/specbake/web/three/specaa_es.glsl.js
              share/specbake/web/three/viewer/index.html share/specbake/web/three/viewer/viewer.mjs)
if(EXISTS "${SOURCE_DIR}/tests/consumers/node_modules/three/build/three.module.js")
  list(APPEND web_files share/specbake/web/vendor/three/LICENSE share/specbake/web/vendor/three/build/three.module.js
                        share/specbake/web/vendor/three/examples/jsm/loaders/GLTFLoader.js
                        share/specbake/web/vendor/three/examples/jsm/libs/basis/basis_transcoder.wasm)
endif()
foreach(f ${web_files})
  if(NOT EXISTS "${prefix}/${f}")
    message(FATAL_ERROR "not installed: ${f}")
  endif()
endforeach()
run(${CMAKE_COMMAND} -S "${SOURCE_DIR}/tests/consumer" -B "${build}" -G "${GENERATOR}"
    -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_BUILD_TYPE=Release)
run(${CMAKE_COMMAND} --build "${build}")
if(NOT last_output MATCHES "specbake: baking")
  message(FATAL_ERROR "the first build did not bake:\n${last_output}")
endif()
run("${build}/consumer")
message(STATUS "${last_output}")

# The library is the pipeline without the simulator: linking it must not bring OpenGL or EGL.
file(GLOB_RECURSE targets_files "${prefix}/*/specbakeTargets*.cmake")
set(targets "")
foreach(f ${targets_files})
  file(READ "${f}" content)
  string(APPEND targets "${content}")
endforeach()
if(targets MATCHES "OpenGL|EGL")
  message(FATAL_ERROR "the installed specbake targets name OpenGL/EGL:\n${targets}")
endif()
run(ldd "${build}/consumer")
if(last_output MATCHES "lib(GL|EGL|OpenGL)[.]")
  message(FATAL_ERROR "the consumer links an OpenGL library:\n${last_output}")
endif()

# Nothing changed: the bake step must not run again.
run(${CMAKE_COMMAND} --build "${build}")
if(last_output MATCHES "specbake: baking")
  message(FATAL_ERROR "the second build baked again:\n${last_output}")
endif()

# The texture the scene references is a dependency only through the depfile.
file(APPEND "${build}/scene/demo/demo_normal.png" " ")
run(${CMAKE_COMMAND} --build "${build}")
if(NOT last_output MATCHES "specbake: baking")
  message(FATAL_ERROR "editing a referenced texture did not rebake:\n${last_output}")
endif()
run("${build}/consumer")
