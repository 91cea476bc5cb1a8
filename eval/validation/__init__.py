"""Published-protocol checks of the matchers: BCAGM synthetic and CMU House protocols, the synthetic CoID benchmark, published numbers."""
