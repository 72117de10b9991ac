"""What a hexapod is: geometry files, presets, the URDF writer and the Pinocchio model with its closures."""
