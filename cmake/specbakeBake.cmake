# specbake_bake(<target> [ALL] SCENES <file>... OUTPUT_DIR <dir> [OPTIONS <arg>...])
#
# Adds one build step per scene: `specbake bake <scene> -o <dir>/<scene name> --depfile ... <options>`,
# and a custom target <target> that depends on all of them. Each step's output is the manifest.json of
# its folder; the depfile specbake writes lists every file the bake read (the scene, its buffers and
# textures), so editing a referenced texture rebakes, and nothing else does. specbake skips a step whose
# manifest shows the outputs are up to date, so a clean rebuild with an intact output folder is cheap.
# Relative SCENES are taken from the current source folder, a relative OUTPUT_DIR from the current binary
# folder. Sets <target>_MANIFESTS in the caller to the manifest paths.
#
#   find_package(specbake REQUIRED)
#   specbake_bake(game_assets ALL SCENES assets/Helmet.gltf assets/Rock.glb OUTPUT_DIR baked
#                 OPTIONS --container ktx2 --isotropic max)
function(specbake_bake target)
  cmake_parse_arguments(PARSE_ARGV 1 SB "ALL" "OUTPUT_DIR" "SCENES;OPTIONS")
  if(NOT SB_SCENES)
    message(FATAL_ERROR "specbake_bake(${target}): SCENES is required")
  endif()
  if(NOT SB_OUTPUT_DIR)
    message(FATAL_ERROR "specbake_bake(${target}): OUTPUT_DIR is required")
  endif()
  if(SB_UNPARSED_ARGUMENTS)
    message(FATAL_ERROR "specbake_bake(${target}): unknown arguments ${SB_UNPARSED_ARGUMENTS}")
  endif()
  cmake_path(ABSOLUTE_PATH SB_OUTPUT_DIR BASE_DIRECTORY "${CMAKE_CURRENT_BINARY_DIR}" NORMALIZE)
  set(manifests)
  foreach(scene IN LISTS SB_SCENES)
    cmake_path(ABSOLUTE_PATH scene BASE_DIRECTORY "${CMAKE_CURRENT_SOURCE_DIR}" NORMALIZE)
    cmake_path(GET scene STEM name)
    set(out "${SB_OUTPUT_DIR}/${name}")
    set(depfile "${CMAKE_CURRENT_BINARY_DIR}/specbake_deps/${target}_${name}.d")
    add_custom_command(
      OUTPUT "${out}/manifest.json"
      COMMAND specbake::cli bake "${scene}" -o "${out}" --depfile "${depfile}" --quiet ${SB_OPTIONS}
      DEPENDS "${scene}" specbake::cli
      DEPFILE "${depfile}"
      COMMENT "specbake: baking ${scene}"
      VERBATIM)
    list(APPEND manifests "${out}/manifest.json")
  endforeach()
  if(SB_ALL)
    add_custom_target(${target} ALL DEPENDS ${manifests})
  else()
    add_custom_target(${target} DEPENDS ${manifests})
  endif()
  set(${target}_MANIFESTS "${manifests}" PARENT_SCOPE)
endfunction()
