# Run by ctest (tests/CMakeLists.txt): the installed package works for a consumer.
#   cmake -DBUILD_DIR=... -DSOURCE_DIR=... -DWORK_DIR=... -DMESH=... -DCXX=... -DGENERATOR=... -P test_package.cmake

function(run what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT code EQUAL 0)
    message(FATAL_ERROR "${what} failed (${code}):\n${out}\n${err}")
  endif()
  set(output "${out}" PARENT_SCOPE)
endfunction()

file(REMOVE_RECURSE "${WORK_DIR}")
set(prefix "${WORK_DIR}/prefix")

# 1. Install into a fresh prefix.
run("cmake --install" ${CMAKE_COMMAND} --install "${BUILD_DIR}" --prefix "${prefix}")
foreach(path lib/libvisproxy.so bin/visproxy bin/visproxy-dask lib/cmake/visproxy/visproxyConfig.cmake
        lib/cmake/visproxy/visproxyConfigVersion.cmake lib/pkgconfig/visproxy.pc
        include/visproxy/render/renderer.h share/visproxy/schemas/scene.schema.json)
  if(NOT EXISTS "${prefix}/${path}")
    message(FATAL_ERROR "the install prefix lacks ${path}")
  endif()
endforeach()

# 2. No installed header includes a private dependency, and every include of a visproxy
# header resolves inside the prefix.
file(GLOB_RECURSE headers "${prefix}/include/visproxy/*.h")
list(LENGTH headers count)
if(count LESS 50)
  message(FATAL_ERROR "only ${count} headers installed")
endif()
foreach(header ${headers})
  file(STRINGS "${header}" lines REGEX "^[ \t]*#[ \t]*include")
  foreach(line ${lines})
    if(line MATCHES "<(CGAL|embree3|tbb|oneapi|OpenMesh|tetgen|assimp)[/.>]")
      message(FATAL_ERROR "${header} includes a private dependency: ${line}")
    endif()
    if(line MATCHES "\"(visproxy/[^\"]+)\"" AND NOT EXISTS "${prefix}/include/${CMAKE_MATCH_1}")
      message(FATAL_ERROR "${header} includes ${CMAKE_MATCH_1}, which is not installed")
    endif()
  endforeach()
endforeach()

# 3. The CLI runs from the prefix.
string(REGEX MATCH "^([0-9]+)\\.([0-9]+)" major_minor "${VERSION}")
set(major ${CMAKE_MATCH_1})
set(minor ${CMAKE_MATCH_2})
math(EXPR next_minor "${minor} + 1")
string(REPLACE "." "\\." version_pattern "${VERSION}")
run("installed visproxy --version" "${prefix}/bin/visproxy" --version)
if(NOT output MATCHES "${version_pattern}")
  message(FATAL_ERROR "installed visproxy --version printed: ${output}")
endif()

# The Dask entry point runs from the prefix with the installed module.
run("installed visproxy-dask --help" ${CMAKE_COMMAND} -E env "PYTHONPATH=${prefix}/lib/python3/dist-packages"
    "${PYTHON}" "${prefix}/bin/visproxy-dask" --help)
if(NOT output MATCHES "--scheduler")
  message(FATAL_ERROR "installed visproxy-dask --help printed: ${output}")
endif()

# 4. A CMake consumer: find_package(visproxy MAJOR.MINOR REQUIRED) and visproxy::visproxy.
run("configuring the consumer" ${CMAKE_COMMAND} -S "${SOURCE_DIR}/tests/package/consumer" -B "${WORK_DIR}/consumer"
    -G "${GENERATOR}" -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_CXX_COMPILER=${CXX})
run("building the consumer" ${CMAKE_COMMAND} --build "${WORK_DIR}/consumer")
run("running the consumer" "${WORK_DIR}/consumer/consumer" "${MESH}")
message(STATUS "consumer: ${output}")
if(NOT output MATCHES "contains the mesh: proved" OR NOT output MATCHES "visproxy ${version_pattern}")
  message(FATAL_ERROR "the consumer printed: ${output}")
endif()

# 5. A version that does not match is refused.
file(WRITE "${WORK_DIR}/wrong/CMakeLists.txt"
     "cmake_minimum_required(VERSION 3.25)\nproject(wrong LANGUAGES CXX)\nfind_package(visproxy ${major}.${next_minor} REQUIRED)\n")
execute_process(COMMAND ${CMAKE_COMMAND} -S "${WORK_DIR}/wrong" -B "${WORK_DIR}/wrong/build" -G "${GENERATOR}"
                -DCMAKE_PREFIX_PATH=${prefix} RESULT_VARIABLE code OUTPUT_QUIET ERROR_QUIET)
if(code EQUAL 0)
  message(FATAL_ERROR "find_package(visproxy ${major}.${next_minor}) accepted version ${VERSION}")
endif()

# 6. pkg-config: the same program compiled with `pkg-config --cflags --libs visproxy` alone,
#    and run without LD_LIBRARY_PATH (the flags carry the library's run path).
find_program(PKG_CONFIG pkg-config REQUIRED)
set(ENV{PKG_CONFIG_PATH} "${prefix}/lib/pkgconfig")
run("pkg-config" ${PKG_CONFIG} --cflags --libs visproxy)
string(STRIP "${output}" flags)
separate_arguments(flags UNIX_COMMAND "${flags}")
unset(ENV{LD_LIBRARY_PATH})
run("compiling with pkg-config's flags" ${CXX} -O1 "${SOURCE_DIR}/tests/package/consumer/main.cpp" ${flags}
    -o "${WORK_DIR}/consumer-pc")
run("running the pkg-config build" "${WORK_DIR}/consumer-pc" "${MESH}")
if(NOT output MATCHES "contains the mesh: proved")
  message(FATAL_ERROR "the pkg-config build printed: ${output}")
endif()

# 7. The installed Python module imports from the prefix alone and builds a proved hull.
set(ENV{PYTHONPATH} "${prefix}/lib/python3/dist-packages")
file(WRITE "${WORK_DIR}/installed_module.py" [[
import sys
import visproxy as vp
vertices, triangles = vp.read_mesh(sys.argv[1])
proxies = vp.build(vertices, triangles, ["hull"])
assert vp.verify(vertices, triangles, proxies)[0]["holds"]
print("python", vp.__version__, vp.__file__)
]])
run("the installed Python module" ${PYTHON} "${WORK_DIR}/installed_module.py" "${MESH}")
if(NOT output MATCHES "python ${version_pattern}" OR NOT output MATCHES "${prefix}/lib/python3/dist-packages/visproxy")
  message(FATAL_ERROR "the installed Python module printed: ${output}")
endif()

# 8. The Embree example, built on its own against the prefix: its image, with a proved
# proxy standing in for the knot (eq. 8 and the control variate), estimates the same
# pixels as the installed `visproxy render --visibility exact` (compare_images.py: every
# 8x8 block within 4.5 standard errors, and power to see a 5 % bias).
run("configuring the example" ${CMAKE_COMMAND} -S "${SOURCE_DIR}/apps/examples" -B "${WORK_DIR}/examples"
    -G "${GENERATOR}" -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_CXX_COMPILER=${CXX})
run("building the example" ${CMAKE_COMMAND} --build "${WORK_DIR}/examples")
set(example "${WORK_DIR}/examples/visproxy-example-embree-shadow")
get_filename_component(mesh_dir "${MESH}" DIRECTORY)
set(knot "${mesh_dir}/knot1.off")
set(scene "${WORK_DIR}/knot-floor.json")
file(WRITE "${scene}" "{\"format\": \"visproxy-scene\", \"format_version\": 1,
 \"description\": \"The knot over a floor under a square light\",
 \"meshes\": {\"floor\": {\"positions\": [[-3, 0, -3], [3, 0, -3], [3, 0, 3], [-3, 0, 3]], \"triangles\": [[0, 2, 1], [0, 3, 2]]},
            \"knot\": {\"file\": \"${knot}\"}},
 \"instances\": [{\"mesh\": \"floor\", \"albedo\": [0.7, 0.7, 0.7]},
   {\"mesh\": \"knot\", \"albedo\": [0.7, 0.5, 0.3], \"transform\": {\"fit\": {\"base\": [0, 0.1, 0], \"height\": 1.0}}}],
 \"lights\": [{\"type\": \"parallelogram\", \"corner\": [-0.5, 3, -0.5], \"edge1\": [1, 0, 0], \"edge2\": [0, 0, 1], \"radiance\": [10, 10, 10]}],
 \"camera\": {\"from\": [0, 2.5, 4], \"at\": [0, 0.5, 0], \"up\": [0, 1, 0], \"fov_degrees\": 45, \"width\": 64, \"height\": 48}}\n")
run("building the knot's proxies" "${prefix}/bin/visproxy" build "${knot}" -o "${WORK_DIR}/knot-proxies" --proxy hull:32 --proxy inside:10)
run("verifying them" "${prefix}/bin/visproxy" verify "${knot}" "${WORK_DIR}/knot-proxies")
foreach(seed 1 2)
  run("visproxy render, seed ${seed}" "${prefix}/bin/visproxy" render "${scene}" -o "${WORK_DIR}/render-${seed}.pfm" --spp 64 --seed ${seed})
endforeach()
foreach(case "hull-32;eq8" "hull-32;control-variate" "inside-10;eq8")
  list(GET case 0 proxy)
  list(GET case 1 estimator)
  foreach(seed 1 2)
    run("the example, ${proxy} ${estimator}" "${example}" "${scene}" knot "${WORK_DIR}/knot-proxies" ${proxy}
        "${WORK_DIR}/example-${seed}.pfm" 64 1${seed} ${estimator})
    if(NOT output MATCHES "\\((outside|inside)\\)")
      message(FATAL_ERROR "the example did not use the proved claim: ${output}")
    endif()
  endforeach()
  run("comparing the example's image (${proxy}, ${estimator}) with visproxy render's" ${PYTHON}
      "${SOURCE_DIR}/tests/package/compare_images.py" "${WORK_DIR}/example-1.pfm" "${WORK_DIR}/example-2.pfm"
      "${WORK_DIR}/render-1.pfm" "${WORK_DIR}/render-2.pfm")
  message(STATUS "${proxy}, ${estimator}: ${output}")
endforeach()
