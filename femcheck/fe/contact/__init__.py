"""Contact between deformable bodies: pairing, penalty with friction, augmented Lagrangian."""
