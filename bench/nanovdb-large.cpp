// A larger NanoVDB grid for bench/nanovdb_scene.py --grid (BENCHMARKS.md,
// "NanoVDB media against pbrt-v4"): a ball of 256 voxels across, 6.6 million
// of them active, of smoothly lumpy density, written uncompressed to
// large.nvdb (33 MB). Build against the NanoVDB headers pbrt-v4 bundles:
//   g++ -O2 -std=c++17 -I<pbrt-v4>/src/ext/openvdb/nanovdb bench/nanovdb-large.cpp -lz -pthread -o nanovdb-large
//   ./nanovdb-large
#define NANOVDB_USE_ZIP
#include <nanovdb/util/GridBuilder.h>
#include <nanovdb/util/IO.h>
#include <cmath>
using namespace nanovdb;
static float noise(float x, float y, float z) {
  return 0.5f + 0.25f * std::sin(x * 0.11f + 1.3f * std::sin(y * 0.07f)) * std::cos(z * 0.13f + 0.9f * std::sin(x * 0.05f))
       + 0.25f * std::sin(0.31f * x + 0.23f * y - 0.17f * z);
}
int main() {
  GridBuilder<float> bd(0.0f, GridClass::FogVolume);
  bd([](const Coord& c) {
       float x = c[0] - 128.f, y = c[1] - 128.f, z = c[2] - 128.f;
       float r = std::sqrt(x * x + y * y + z * z) / 120.f;
       if (r >= 1.f) return 0.0f;
       float d = (1.f - r) * noise(c[0], c[1], c[2]) * 2.f;
       return d > 0.02f ? d : 0.0f;
     }, CoordBBox(Coord(0, 0, 0), Coord(255, 255, 255)));
  auto h = bd.getHandle<>(0.01, Vec3d(0.2, -0.6, 0.4), "density");
  io::writeGrid("large.nvdb", h, io::Codec::NONE);
  auto* g = h.grid<float>();
  printf("active %llu bbox %g %g %g - %g %g %g\n", (unsigned long long)g->activeVoxelCount(),
         g->worldBBox().min()[0], g->worldBBox().min()[1], g->worldBBox().min()[2],
         g->worldBBox().max()[0], g->worldBBox().max()[1], g->worldBBox().max()[2]);
}
