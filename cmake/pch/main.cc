// The program that builds the executables' and the tests' precompiled headers
// (cmake/ParallaxPrecompiledHeaders.cmake); it is never run.
int main() { return 0; }
