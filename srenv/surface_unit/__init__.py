"""The surface unit: prescribed polished-rod motion (harmonic, conventional beam unit, measured), the API 11E
conventional unit (four-bar kinematics, torque factor), its catalogue, measured dynamometer motion, and the gearbox
torque and power over simulated strokes."""
