// placeholder so the library has a source until reference/ lands; delete when real sources exist
