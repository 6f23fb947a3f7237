# palpable_module(NAME DIR DEPS...): one static library per module from every .cpp in DIR
# (non-recursive). Sources are globbed with CONFIGURE_DEPENDS so adding a file needs no edit here.
function(palpable_module name dir)
  file(GLOB _sources CONFIGURE_DEPENDS "${dir}/*.cpp")
  file(GLOB _headers CONFIGURE_DEPENDS "${dir}/*.hpp")
  # Headers include each other as "core/x.hpp": the source root while building, include/palpable
  # once installed (cmake --install; palpableConfig.cmake exports palpable::palpable).
  set(_includes $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}> $<INSTALL_INTERFACE:include/palpable>)
  if(_sources)
    add_library(${name} STATIC ${_sources} ${_headers})
    target_include_directories(${name} PUBLIC ${_includes})
    target_link_libraries(${name} PUBLIC ${ARGN})
  else()
    add_library(${name} INTERFACE)
    target_include_directories(${name} INTERFACE ${_includes})
    target_link_libraries(${name} INTERFACE ${ARGN})
  endif()
  # The five simulator modules are installed; cross-check and tool libraries are not.
  if(name MATCHES "^palpable_(core|distance|impulse|scheduler|scenarios)$")
    file(RELATIVE_PATH _module ${PROJECT_SOURCE_DIR} ${dir})
    install(TARGETS ${name} EXPORT palpableTargets ARCHIVE DESTINATION lib)
    # What the build applies to everything (add_compile_definitions, add_link_options) must reach
    # a program built against the installed package too: a sanitized library links only with the
    # sanitizer runtimes, and a checked build's inline PALPABLE_DCHECKs must mean the same in
    # the program as in the library.
    if(PALPABLE_SANITIZE)
      target_link_options(${name} INTERFACE $<INSTALL_INTERFACE:-fsanitize=address,undefined>)
    endif()
    if(PALPABLE_CHECKED)
      target_compile_definitions(${name} INTERFACE $<INSTALL_INTERFACE:PALPABLE_CHECKED=1>)
    endif()
    # A header named *_detail.hpp or *_impl.hpp is private to its module's own .cpp files (the
    # shared helpers or state of one concept's implementation): not installed.
    list(FILTER _headers EXCLUDE REGEX "_(detail|impl)\\.hpp$")
    install(FILES ${_headers} DESTINATION include/palpable/${_module})
  endif()
endfunction()
