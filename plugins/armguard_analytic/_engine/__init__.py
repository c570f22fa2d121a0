"""The analytic backend's engine: Ranger's cycle as one fused numba call (moved from armguard.detect)."""
