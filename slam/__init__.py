"""Odometry-free EKF-SLAM with line and corner landmarks, and trajectory scoring."""
