"""BSDFs and the device-side material table."""
