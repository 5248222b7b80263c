"""Triangle setup (seeds 001, 002): not built yet; see the quadratic-shading issue."""
