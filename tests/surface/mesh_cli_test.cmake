# ctest script for `fluiddemo mesh` (run with -DEXE=<fluiddemo> -DDATA=<tests/data> -DWORK=<dir>).
# Checks: a good run writes a mesh with the README's triangle count; an existing output is not
# replaced without --force; NaN and malformed lines are reported with file and line; unknown
# output formats are refused.
file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")

function(run_mesh expect_rc out_var err_var)
  execute_process(COMMAND "${EXE}" mesh ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL ${expect_rc})
    message(FATAL_ERROR "fluiddemo mesh ${ARGN}: exit ${rc}, expected ${expect_rc}\nstdout: ${out}\nstderr: ${err}")
  endif()
  set(${out_var} "${out}" PARENT_SCOPE)
  set(${err_var} "${err}" PARENT_SCOPE)
endfunction()

run_mesh(0 out err --in "${DATA}/blob.xyz" --out "${WORK}/blob.obj" --cube 0.3 --threads 2 --stats)
if(NOT out MATCHES "triangles +8288")
  message(FATAL_ERROR "expected 8288 triangles (tests/data/README.md), got:\n${out}")
endif()
file(STRINGS "${WORK}/blob.obj" faces REGEX "^f ")
list(LENGTH faces nfaces)
if(NOT nfaces EQUAL 8288)
  message(FATAL_ERROR "blob.obj has ${nfaces} faces, expected 8288")
endif()
file(STRINGS "${WORK}/blob.obj" normals REGEX "^vn ")
list(LENGTH normals nnormals)
if(nnormals EQUAL 0)
  message(FATAL_ERROR "blob.obj has no normals")
endif()

# Existing output: refused without --force, replaced with it.
run_mesh(1 out err --in "${DATA}/blob.xyz" --out "${WORK}/blob.obj" --cube 0.3)
if(NOT err MATCHES "exists")
  message(FATAL_ERROR "expected a refusal to overwrite, got: ${err}")
endif()
run_mesh(0 out err --in "${DATA}/blob.xyz" --out "${WORK}/blob.obj" --cube 0.3 --force)

# Binary PLY output.
run_mesh(0 out err --in "${DATA}/blob.xyz" --out "${WORK}/blob.ply" --cube 0.3)
file(READ "${WORK}/blob.ply" header LIMIT 300)
if(NOT header MATCHES "element face 8288")
  message(FATAL_ERROR "blob.ply header wrong: ${header}")
endif()

# Bad input: NaN, malformed line, missing file, unknown output format.
file(WRITE "${WORK}/nan.xyz" "1 2 3\n4 nan 6\n")
run_mesh(1 out err --in "${WORK}/nan.xyz" --out "${WORK}/nan.obj")
if(NOT err MATCHES "nan.xyz:2")
  message(FATAL_ERROR "NaN not reported with file:line: ${err}")
endif()
file(WRITE "${WORK}/short.xyz" "1 2 3\n4 5\n")
run_mesh(1 out err --in "${WORK}/short.xyz" --out "${WORK}/short.obj")
if(NOT err MATCHES "short.xyz:2")
  message(FATAL_ERROR "malformed line not reported with file:line: ${err}")
endif()
run_mesh(1 out err --in "${WORK}/missing.xyz" --out "${WORK}/missing.obj")
if(NOT err MATCHES "missing.xyz")
  message(FATAL_ERROR "missing file not named: ${err}")
endif()
run_mesh(2 out err --in "${DATA}/blob.xyz" --out "${WORK}/blob.stl")
if(EXISTS "${WORK}/nan.obj" OR EXISTS "${WORK}/short.obj" OR EXISTS "${WORK}/blob.stl")
  message(FATAL_ERROR "a failed run left an output file behind")
endif()
