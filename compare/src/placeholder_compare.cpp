// placeholder so the library has a source until compare/ lands; delete when real sources exist
