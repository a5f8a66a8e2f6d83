"""The model layer: flexspline geometry, compliance chain, the drive and its effects, catalog data."""

from hdsim.model.drive import (SLOTS, Calibration, ComplianceChain, DriveData, HarmonicDrive,
                               WaveGenerator, compliance_chain)

__all__ = ["SLOTS", "Calibration", "ComplianceChain", "DriveData", "HarmonicDrive", "WaveGenerator",
           "compliance_chain"]
