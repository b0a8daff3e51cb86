# teleop_set_warnings(<target>): the project's one warning policy.
function(teleop_set_warnings target)
  target_compile_options(${target} PRIVATE
    $<$<COMPILE_LANGUAGE:CXX>:-Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor
      -Wold-style-cast -Wcast-align -Wunused -Woverloaded-virtual
      -Wdouble-promotion -Wformat=2 -Wimplicit-fallthrough>)
  if(TELEOP_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()

# teleop_configure_target(<target>): warnings plus the project-wide definitions.
function(teleop_configure_target target)
  teleop_set_warnings(${target})
  target_compile_definitions(${target} PRIVATE TELEOP_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
    TELEOP_PYTHON3="${TELEOP_PYTHON3}")
endfunction()
