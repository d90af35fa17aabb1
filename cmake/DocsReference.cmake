# Writes or checks the generated reference pages docs/reference/{cli,records}.md: each is what
# `microsim reference PAGE` prints.
#   cmake -DMICROSIM=<program> -DDOCS=<docs/reference> -DMODE=write|check -P DocsReference.cmake
# check fails, naming the page and how to regenerate it, when a committed page differs.
foreach(var MICROSIM DOCS MODE)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "DocsReference.cmake needs -D${var}=...")
  endif()
endforeach()
set(stale "")
foreach(page cli records)
  execute_process(COMMAND "${MICROSIM}" reference ${page} OUTPUT_VARIABLE text RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "`microsim reference ${page}` failed (exit ${rc})")
  endif()
  set(committed "${DOCS}/${page}.md")
  if(MODE STREQUAL "write")
    file(WRITE "${committed}" "${text}")
    message(STATUS "wrote ${committed}")
    continue()
  endif()
  set(old "")
  if(EXISTS "${committed}")
    file(READ "${committed}" old)
  endif()
  if(NOT old STREQUAL text)
    list(APPEND stale ${page})
    # Show the difference (diff is optional: the message alone says what to do).
    set(fresh "${CMAKE_CURRENT_BINARY_DIR}/reference-${page}.md")
    file(WRITE "${fresh}" "${text}")
    find_program(DIFF diff)
    if(DIFF)
      execute_process(COMMAND "${DIFF}" -u "${committed}" "${fresh}")
    endif()
  endif()
endforeach()
if(stale)
  list(JOIN stale " and " stale_pages)
  message(FATAL_ERROR "docs/reference: ${stale_pages} differ from what the program prints "
                      "(`microsim reference PAGE`). Regenerate them with\n"
                      "  cmake --build build --target docs_reference\n"
                      "and commit the result.")
endif()
