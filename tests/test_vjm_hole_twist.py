"""Three-hole reconstruction of the HISS platform twist (seed 001 sec. 3; issue 21 item 3 acceptance 1)."""
import numpy as np
from scipy.spatial.transform import Rotation

from femcheck.vjm.hole_twist import circle_centre_and_normal, platform_twist


def test_three_hole_reconstruction_recovers_a_known_twist():
    rng = np.random.default_rng(1)
    m = 20
    centre = rng.uniform(-0.1, 0.1, (m, 3))
    ang = np.sort(rng.uniform(0, 2 * np.pi, (m, 3)), axis=1)
    local = 0.03 * np.stack([np.cos(ang), np.sin(ang), np.zeros_like(ang)], axis=-1)   # 30 mm circle
    R0 = Rotation.random(m, random_state=2)
    before = centre[:, None] + np.einsum("mij,mpj->mpi", R0.as_matrix(), local)
    c, n = circle_centre_and_normal(before)
    np.testing.assert_allclose(c, centre, atol=1e-12)            # round-off on 0.1 m coordinates
    np.testing.assert_allclose(np.abs(np.einsum("mk,mk->m", n, R0.as_matrix()[:, :, 2])), 1.0, atol=1e-12)
    twist = np.column_stack([rng.normal(0, 1e-3, (m, 3)), rng.normal(0, 1e-2, (m, 3))])   # mm and 0.5 deg order
    dR = Rotation.from_rotvec(twist[:, 3:]).as_matrix()
    after = centre[:, None] + twist[:, None, :3] + np.einsum("mij,mpj->mpi", dR, before - centre[:, None])
    # acceptance: 1e-9 (round-off of the SVD and circumcentre, far below it)
    np.testing.assert_allclose(platform_twist(before, after), twist, atol=1e-9)
