#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <OpenEXR/ImfTiledOutputFile.h>
#include <Imath/half.h>
#include <string>
#include <vector>
using namespace Imf;
int main(int argc, char** argv) {
  const std::string dir = argv[1];
  const int w = 8, h = 6, x0 = -1, y0 = 2;
  std::vector<half> a(w * h); std::vector<float> b(w * h); std::vector<uint32_t> c(w * h);
  for (int i = 0; i < w * h; ++i) { a[i] = half(i * 0.37f - 3.0f); b[i] = i % 3 ? 1.0f : -i * 12.5f; c[i] = 4000000000u - i * 977u; }
  auto header = [&](Compression comp) {
    Header hd(Imath::Box2i({x0, y0}, {x0 + w - 1, y0 + h - 1}), Imath::Box2i({x0, y0}, {x0 + w - 1, y0 + h - 1}));
    hd.compression() = comp;
    hd.channels().insert("A", Channel(HALF)); hd.channels().insert("light.sun.vis", Channel(FLOAT)); hd.channels().insert("object_id", Channel(UINT));
    hd.insert("shadowlab:meta", StringAttribute("{\"kind\":\"reference\"}"));
    return hd;
  };
  FrameBuffer fb;
  const ptrdiff_t o = x0 + ptrdiff_t(y0) * w;
  fb.insert("A", Slice(HALF, (char*)(a.data() - o), 2, 2 * w));
  fb.insert("light.sun.vis", Slice(FLOAT, (char*)(b.data() - o), 4, 4 * w));
  fb.insert("object_id", Slice(UINT, (char*)(c.data() - o), 4, 4 * w));
  struct { const char* n; Compression c; } cs[] = {{"none", NO_COMPRESSION}, {"rle", RLE_COMPRESSION}, {"zips", ZIPS_COMPRESSION}, {"zip", ZIP_COMPRESSION}, {"piz", PIZ_COMPRESSION}, {"pxr24", PXR24_COMPRESSION}, {"b44", B44_COMPRESSION}};
  for (auto& k : cs) { OutputFile out((dir + "/" + k.n + ".exr").c_str(), header(k.c)); out.setFrameBuffer(fb); out.writePixels(h); }
  Header th = header(ZIP_COMPRESSION); th.setTileDescription(TileDescription(4, 4, ONE_LEVEL));
  TiledOutputFile t((dir + "/tiled_zip.exr").c_str(), th); t.setFrameBuffer(fb); t.writeTiles(0, t.numXTiles() - 1, 0, t.numYTiles() - 1);
}
