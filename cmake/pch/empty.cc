// The translation unit that builds the layer libraries' precompiled header
// (cmake/ParallaxPrecompiledHeaders.cmake); it has nothing of its own.
