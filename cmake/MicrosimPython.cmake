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
# Where `cmake --install` puts the Python package, relative to the prefix: the interpreter's own
# folder for the prefix's platform-specific packages (Debian's python3: lib/python3.X/dist-packages,
# which is on its sys.path for /usr/local and /usr), so that `import microsim` needs no PYTHONPATH
# when the prefix is the interpreter's.
if(NOT DEFINED MICROSIM_PYTHON_INSTALL_DIR)
  execute_process(COMMAND ${Python3_EXECUTABLE} -c
    "import os, sysconfig; print(os.path.relpath(sysconfig.get_path('platlib'), sysconfig.get_path('data')))"
    OUTPUT_VARIABLE py_dir OUTPUT_STRIP_TRAILING_WHITESPACE RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0 OR py_dir STREQUAL "" OR py_dir MATCHES "^\\.\\.")
    set(py_dir ${CMAKE_INSTALL_LIBDIR}/python3/dist-packages)
  endif()
  set(MICROSIM_PYTHON_INSTALL_DIR ${py_dir} CACHE PATH
      "Install folder of the Python package, relative to the install prefix")
endif()
