"""PyBullet office worlds that emulate a SICK LMS200, with exact ground truth."""
