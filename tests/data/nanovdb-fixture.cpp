// The NanoVDB test fixture tests/data/small-zip.nvdb, written by NanoVDB's
// own writer (version 32.3, as bundled with pbrt-v4: build with
// g++ -std=c++17 -I<pbrt-v4>/src/ext/openvdb/nanovdb nanovdb-fixture.cpp -lz -pthread).
// It also prints voxel values and trilinear samples to small.txt.
#define NANOVDB_USE_ZIP
#include <nanovdb/util/GridBuilder.h>
#include <nanovdb/util/IO.h>
#include <nanovdb/util/SampleFromVoxels.h>
#include <cstdio>
#include <vector>
using namespace nanovdb;
static float dens(int i,int j,int k){ if(i>=24&&i<=31&&j>=8&&j<=15&&k>=16&&k<=23) return 0.9f; return 0.01f*(float)(((i+2*j+3*k)%97+97)%97)+0.1f; }
static bool inside(int i,int j,int k){ double x=(i-20)/40.0,y=(j-10)/20.0,z=(k-20)/20.0; return x*x+y*y+z*z<=1.0; }
int main(int argc,char**argv){
  GridBuilder<float> bd(0.0f, GridClass::FogVolume);
  // The functor form prunes constant leaves into tiles (the 8^3 block of 0.9).
  bd([](const Coord& c) { return inside(c[0],c[1],c[2]) ? dens(c[0],c[1],c[2]) : 0.0f; }, CoordBBox(Coord(-20,-10,0), Coord(60,30,40)));
  auto hd = bd.getHandle<>(0.05, Vec3d(0.3,-0.2,0.1), "density");
  GridBuilder<float> bt(0.0f, GridClass::FogVolume);
  auto b = bt.getAccessor();
  for(int i=0;i<=40;i++)for(int j=0;j<=20;j++)for(int k=0;k<=30;k++) b.setValue(Coord(i,j,k), 500.0f+10.0f*i+3.0f*j-k);
  auto ht = bt.getHandle<>(0.1, Vec3d(-0.5,0.0,0.2), "temperature");
  std::vector<GridHandle<>> hs; hs.push_back(std::move(ht)); hs.push_back(std::move(hd));
  io::writeGrids("small.nvdb", hs, io::Codec::NONE);
  io::writeGrids("small-zip.nvdb", hs, io::Codec::ZIP);
  auto* g = hs[1].grid<float>();
  FILE*f=fopen("small.txt","w");
  auto acc = g->getAccessor();
  int pts[][3]={{20,10,20},{-20,10,20},{60,10,20},{-21,10,20},{0,0,0},{20,-10,20},{20,30,20},{20,10,0},{20,10,40},{7,8,9},{-5,3,17},{33,-2,25},{100,100,100},{-1000,5,5},{15,15,15},{8,8,8},{-8,-8,0},{40,20,30}};
  for(auto&p:pts) fprintf(f,"v %d %d %d %.9g\n",p[0],p[1],p[2],acc.getValue(Coord(p[0],p[1],p[2])));
  using S = SampleFromVoxels<NanoGrid<float>::TreeType,1,false>;
  S s(g->tree());
  double wp[][3]={{1.3,0.3,1.1},{0.51,0.02,0.33},{1.05,0.41,1.27},{0.0,0.0,0.0},{2.2,0.9,2.0},{0.3,-0.2,0.1},{0.777,0.123,0.456},{3.3,0.5,1.2},{1.0001,0.2999,0.9}};
  for(auto&w:wp){ Vec3f idx = g->worldToIndexF(Vec3f((float)w[0],(float)w[1],(float)w[2])); fprintf(f,"s %.9g %.9g %.9g %.9g\n",w[0],w[1],w[2], (double)s(idx)); }
  auto bb = g->worldBBox(); fprintf(f,"bbox %.9g %.9g %.9g %.9g %.9g %.9g\n",bb.min()[0],bb.min()[1],bb.min()[2],bb.max()[0],bb.max()[1],bb.max()[2]);
  fclose(f);
}
