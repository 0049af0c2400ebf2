// placeholder so the library has a source until raster/ lands; delete when real sources exist
