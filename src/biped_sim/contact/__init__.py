"""Foot-ground contact: geometry (detection, scuffing guard), normal force laws and friction laws."""
