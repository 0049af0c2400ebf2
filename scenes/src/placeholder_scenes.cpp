// placeholder until scenes/ lands
