# TELEOP_SANITIZE=address -> AddressSanitizer + UndefinedBehaviorSanitizer
# TELEOP_SANITIZE=thread  -> ThreadSanitizer
if(TELEOP_SANITIZE STREQUAL "address")
  add_compile_options(-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined)
  add_link_options(-fsanitize=address,undefined)
elseif(TELEOP_SANITIZE STREQUAL "thread")
  add_compile_options(-fsanitize=thread -fno-omit-frame-pointer)
  add_link_options(-fsanitize=thread)
elseif(NOT TELEOP_SANITIZE STREQUAL "")
  message(FATAL_ERROR "TELEOP_SANITIZE='${TELEOP_SANITIZE}' is not one of '', 'address', 'thread'")
endif()
if(TELEOP_EIGEN_NO_MALLOC)
  add_compile_definitions(EIGEN_RUNTIME_NO_MALLOC)
endif()
