# The Python interpreter used by the report, the analysis tests and the Python module: the first
# python3 on the PATH that imports numpy (a bare interpreter earlier on the PATH, e.g. a pyenv
# shim, is skipped). -DPython3_EXECUTABLE=... chooses one explicitly.
if(NOT Python3_EXECUTABLE AND CMAKE_VERSION VERSION_GREATER_EQUAL 3.25)
  function(microsim_python_has_numpy result candidate)
    execute_process(COMMAND "${candidate}" -c "import numpy" RESULT_VARIABLE rc
                    OUTPUT_QUIET ERROR_QUIET)
    if(NOT rc EQUAL 0)
      set(${result} FALSE PARENT_SCOPE)
    endif()
  endfunction()
  find_program(MICROSIM_PYTHON_WITH_NUMPY NAMES python3 VALIDATOR microsim_python_has_numpy)
  if(MICROSIM_PYTHON_WITH_NUMPY)
    set(Python3_EXECUTABLE "${MICROSIM_PYTHON_WITH_NUMPY}" CACHE FILEPATH "Python interpreter")
  endif()
endif()
find_package(Python3 REQUIRED COMPONENTS Interpreter OPTIONAL_COMPONENTS Development.Module NumPy)
# Where the module is built (python/CMakeLists.txt): PYTHONPATH for the report and the tests.
set(MICROSIM_PYTHON_DIR ${CMAKE_BINARY_DIR}/python)
