// The unit that compiles the test executables' shared precompiled header (tests/CMakeLists.txt,
// vlab_test_pch); it holds nothing of its own.
