/* Forced into every C++ file of the sanitizer builds (fuzz/CMakeLists.txt): toml++ is
 * compiled from its headers (header-only mode) into the code that uses it, so that its
 * parser is instrumented like the rest: Debian's libtomlplusplus.so is built without
 * sanitizers, so UBSan could not see undefined behaviour inside it (issue 10: inputs reach
 * its "unreachable" code) and libFuzzer would get no coverage of the parser. The package's
 * CMake target sets -DTOML_HEADER_ONLY=0 -DTOML_SHARED_LIB=1; a forced include comes after
 * the command line's definitions, so these win. */
#undef TOML_HEADER_ONLY
#define TOML_HEADER_ONLY 1
#undef TOML_SHARED_LIB
#define TOML_SHARED_LIB 0
