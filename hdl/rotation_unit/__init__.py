"""Angular vector rotation (seed 003 §3.1): not built yet; see the angular bump-mapping issue."""
