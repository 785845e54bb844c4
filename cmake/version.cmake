# Writes OUT, a header with the commit the build is made from (`git describe
# --always --dirty` in SRC, or "unknown" outside a clone), and rewrites it
# only when that changes, so that a build recompiles one file per commit.
execute_process(COMMAND git -C "${SRC}" describe --always --dirty --abbrev=7
                OUTPUT_VARIABLE describe OUTPUT_STRIP_TRAILING_WHITESPACE
                RESULT_VARIABLE status ERROR_QUIET)
if(NOT status EQUAL 0 OR describe STREQUAL "")
  set(describe "unknown")
endif()
set(text "// Written by cmake/version.cmake at build time.\n#define MC_BUILD_COMMIT \"${describe}\"\n")
if(EXISTS "${OUT}")
  file(READ "${OUT}" old)
else()
  set(old "")
endif()
if(NOT old STREQUAL text)
  file(WRITE "${OUT}" "${text}")
endif()
