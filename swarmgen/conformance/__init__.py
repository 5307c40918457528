"""W3C SCXML IRP conformance harness (not imported by the compiler)."""
