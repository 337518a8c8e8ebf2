# Writes the Lua file IN as a C++ string constant into OUT (cmake -P).
file(READ ${IN} text)
file(WRITE ${OUT} "// Generated from lua/stage_prelude.lua: do not edit.\nnamespace alloy::lua {\nextern const char* const kStagePreludeSource;\nconst char* const kStagePreludeSource = R\"alloy_prelude(${text})alloy_prelude\";\n}  // namespace alloy::lua\n")
