# The layering check (ctest `layering`): the harness core knows no physics,
# no Lua and no application, and lua/ binds what plugins declare without
# naming a resolver (issue 15: a second engine must plug in without edits
# there).
#   runtime/  includes nothing from lua/, resolvers/ or apps/
#   lua/      includes no resolvers/ header, and names neither the rigid body
#             nor the collisions set in a string (it finds them by what the
#             plugins declare: PluginDef::functions, PluginDef::contacts)
# Run: cmake -DSRC=<source dir> -P tests/layering.cmake (fails listing file:line).
if(NOT SRC)
  message(FATAL_ERROR "layering.cmake: pass -DSRC=<source dir>")
endif()
set(problems "")

function(check_files dir globs regex why)
  set(files "")
  foreach(g ${globs})
    file(GLOB_RECURSE found "${SRC}/${dir}/${g}")
    list(APPEND files ${found})
  endforeach()
  foreach(f ${files})
    file(STRINGS "${f}" lines)
    set(n 0)
    foreach(line IN LISTS lines)
      math(EXPR n "${n} + 1")
      if(line MATCHES "${regex}")
        file(RELATIVE_PATH rel "${SRC}" "${f}")
        string(STRIP "${line}" text)
        set(problems "${problems}${rel}:${n}: ${why}: ${text}\n" PARENT_SCOPE)
        set(problems "${problems}${rel}:${n}: ${why}: ${text}\n")
      endif()
    endforeach()
  endforeach()
endfunction()

check_files(runtime "*.hpp;*.cpp" "^[ \t]*#[ \t]*include[ \t]*\"(lua|resolvers|apps)/"
            "runtime/ includes a higher layer")
check_files(lua "*.hpp;*.cpp;*.lua" "^[ \t]*#[ \t]*include[ \t]*\"resolvers/"
            "lua/ includes a resolver header")
check_files(lua "*.hpp;*.cpp" "\"(rigid_body|collisions)[\".@]"
            "lua/ names a resolver (bind what PluginDef declares)")

if(problems)
  message(FATAL_ERROR "layering check failed:\n${problems}")
endif()
message(STATUS "layering check: clean")
