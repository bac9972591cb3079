"""The real bench: calibrate the table plane to each camera, show the operator where each object goes, and measure
where it went (overlays in Rerun, colour checks, measured cost)."""
