// Linked into every executable that opens a GL context: the GL test executables (tests labelled
// "gl", see tests/CMakeLists.txt) and fluiddemo (game/CMakeLists.txt).
#if defined(__SANITIZE_ADDRESS__)
// LeakSanitizer is off for GL binaries only: creating and destroying one SDL offscreen GL
// context leaks inside the Mesa/LLVM driver (a bare C program doing just that reports 7059
// bytes in 257 allocations under ASan), and the driver is dlclose()d before LSan runs, so its
// frames cannot be symbolised or suppressed. ASan's other checks stay on, and the non-GL
// tests (which cover the game's code too) keep their leak checks.
extern "C" const char* __lsan_default_options() { return "detect_leaks=0"; }
#endif
