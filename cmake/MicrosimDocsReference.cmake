# The documentation's pages generated from the program (docs/reference/cli.md, records.md) and
# the commands its pages show (fenced `sh` blocks, run by tests/run_doc_blocks.py).

# Regenerates the reference pages in the source tree:
#   cmake --build build --target docs_reference
add_custom_target(docs_reference
  COMMAND ${CMAKE_COMMAND} -DMICROSIM=$<TARGET_FILE:microsim> -DDOCS=${CMAKE_SOURCE_DIR}/docs/reference
          -DMODE=write -P ${CMAKE_SOURCE_DIR}/cmake/DocsReference.cmake
  DEPENDS microsim
  COMMENT "Writing docs/reference/cli.md and records.md from the program")

# The examples marked `# long example` (not run by the test doc_blocks):
#   cmake --build build --target doc_blocks_long
add_custom_target(doc_blocks_long
  COMMAND ${Python3_EXECUTABLE} ${CMAKE_SOURCE_DIR}/tests/run_doc_blocks.py --long
          --root ${CMAKE_SOURCE_DIR} --bin-dir $<TARGET_FILE_DIR:microsim>
          --pythonpath ${MICROSIM_PYTHON_DIR}
  DEPENDS microsim USES_TERMINAL
  COMMENT "Running the documentation's long examples")

if(MICROSIM_TESTS)
  # The committed reference pages are what the program prints.
  add_test(NAME docs_reference_current
           COMMAND ${CMAKE_COMMAND} -DMICROSIM=$<TARGET_FILE:microsim>
                   -DDOCS=${CMAKE_SOURCE_DIR}/docs/reference -DMODE=check
                   -P ${CMAKE_SOURCE_DIR}/cmake/DocsReference.cmake)
  # Every field the measurements write into their rows is on the records page (small runs).
  add_test(NAME docs_records_complete
           COMMAND ${Python3_EXECUTABLE} ${CMAKE_SOURCE_DIR}/tests/check_record_fields.py
                   --microsim $<TARGET_FILE:microsim> --page ${CMAKE_SOURCE_DIR}/docs/reference/records.md)
  set_tests_properties(docs_records_complete PROPERTIES TIMEOUT 120 LABELS python)
  # Every `sh` block of README.md and docs/ runs (page by page, in a fresh folder).
  add_test(NAME doc_blocks
           COMMAND ${Python3_EXECUTABLE} ${CMAKE_SOURCE_DIR}/tests/run_doc_blocks.py
                   --root ${CMAKE_SOURCE_DIR} --bin-dir $<TARGET_FILE_DIR:microsim>
                   --pythonpath ${MICROSIM_PYTHON_DIR})
  set_tests_properties(doc_blocks PROPERTIES TIMEOUT 600 LABELS python)
endif()
