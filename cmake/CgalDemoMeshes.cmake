# visproxy_add_cgal_meshes(MESH...)
#
# Adds the target `cgal_meshes` (part of ALL) that extracts the named meshes from
# Debian's libcgal-demo package into ${VISPROXY_MESH_DIR} (build tree) with
# cmake/fetch_cgal_meshes.sh. Nothing large is committed to the repository.
set(VISPROXY_MESH_DIR "${CMAKE_BINARY_DIR}/meshes" CACHE INTERNAL "Extracted libcgal-demo meshes")

function(visproxy_add_cgal_meshes)
  set(outputs "")
  foreach(mesh IN LISTS ARGN)
    list(APPEND outputs "${VISPROXY_MESH_DIR}/${mesh}")
  endforeach()
  add_custom_command(
    OUTPUT ${outputs}
    COMMAND "${CMAKE_CURRENT_SOURCE_DIR}/cmake/fetch_cgal_meshes.sh" "${VISPROXY_MESH_DIR}" ${ARGN}
    COMMENT "Extracting meshes from Debian's libcgal-demo into ${VISPROXY_MESH_DIR}"
    VERBATIM)
  add_custom_target(cgal_meshes ALL DEPENDS ${outputs})
endfunction()

# The target `assimp_models` (part of ALL) unpacks Debian's assimp-testmodels into
# ${VISPROXY_ASSIMP_MODEL_DIR} (build tree) with cmake/fetch_assimp_models.sh.
set(VISPROXY_ASSIMP_MODEL_DIR "${CMAKE_BINARY_DIR}/assimp-testmodels/models" CACHE INTERNAL "Unpacked assimp-testmodels")
add_custom_command(
  OUTPUT "${CMAKE_BINARY_DIR}/assimp-testmodels/.unpacked"
  COMMAND "${CMAKE_CURRENT_SOURCE_DIR}/cmake/fetch_assimp_models.sh" "${CMAKE_BINARY_DIR}/assimp-testmodels"
  COMMENT "Unpacking Debian's assimp-testmodels into ${CMAKE_BINARY_DIR}/assimp-testmodels"
  VERBATIM)
add_custom_target(assimp_models ALL DEPENDS "${CMAKE_BINARY_DIR}/assimp-testmodels/.unpacked")
