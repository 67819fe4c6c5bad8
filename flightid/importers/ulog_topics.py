"""The PX4 uORB topics flightid writes to and reads from ULog files, with the fields it
uses, as PX4's ``msg/*.msg`` define them (ULog types; the first field is always
``uint64_t timestamp``, microseconds since boot). Units are PX4's: rad, rad/s, m/s^2,
m/s, Pa, deg (latitude, longitude), m.
"""

from __future__ import annotations

TOPICS: dict[str, tuple[tuple[str, str], ...]] = {
    "sensor_combined": (
        ("uint64_t", "timestamp"), ("float[3]", "gyro_rad"), ("uint32_t", "gyro_integral_dt"),
        ("int32_t", "accelerometer_timestamp_relative"), ("float[3]", "accelerometer_m_s2"),
        ("uint32_t", "accelerometer_integral_dt"), ("uint8_t", "accelerometer_clipping"),
        ("uint8_t", "gyro_clipping"), ("uint8_t", "accel_calibration_count"),
        ("uint8_t", "gyro_calibration_count")),
    "vehicle_angular_velocity": (
        ("uint64_t", "timestamp"), ("uint64_t", "timestamp_sample"), ("float[3]", "xyz"),
        ("float[3]", "xyz_derivative")),
    "vehicle_attitude": (
        ("uint64_t", "timestamp"), ("uint64_t", "timestamp_sample"), ("float[4]", "q"),
        ("float[4]", "delta_q_reset"), ("uint8_t", "quat_reset_counter")),
    "airspeed": (
        ("uint64_t", "timestamp"), ("uint64_t", "timestamp_sample"),
        ("float", "indicated_airspeed_m_s"), ("float", "true_airspeed_m_s"),
        ("float", "air_temperature_celsius"), ("float", "confidence")),
    "differential_pressure": (
        ("uint64_t", "timestamp"), ("uint64_t", "timestamp_sample"), ("uint32_t", "device_id"),
        ("float", "differential_pressure_pa"), ("float", "temperature"),
        ("uint32_t", "error_count")),
    "airflow_aoa": (("uint64_t", "timestamp"), ("float", "aoa_rad"), ("bool", "valid")),
    "airflow_slip": (("uint64_t", "timestamp"), ("float", "slip_rad"), ("bool", "valid")),
    "actuator_outputs": (
        ("uint64_t", "timestamp"), ("uint32_t", "noutputs"), ("float[16]", "output")),
    "actuator_servos": (
        ("uint64_t", "timestamp"), ("uint64_t", "timestamp_sample"), ("float[8]", "control")),
    "vehicle_air_data": (
        ("uint64_t", "timestamp"), ("uint64_t", "timestamp_sample"),
        ("uint32_t", "baro_device_id"), ("float", "baro_alt_meter"),
        ("float", "baro_temp_celcius"), ("float", "baro_pressure_pa"), ("float", "rho"),
        ("float", "eas2tas"), ("uint8_t", "calibration_count")),
    "vehicle_global_position": (
        ("uint64_t", "timestamp"), ("uint64_t", "timestamp_sample"), ("double", "lat"),
        ("double", "lon"), ("float", "alt")),
}

# PX4's control allocation parameters that say which output drives which surface
# (PX4 v1.13 and later): PWM_MAIN_FUNCn is an output's function, 201 + i for the control
# surface i (``CA_SV_CS{i}_TYPE``, trim ``CA_SV_CS{i}_TRIM`` in -1..1 of the output's
# half range), 101 for motor 1; PWM_MAIN_MINn and PWM_MAIN_MAXn the output's range (us);
# PWM_MAIN_REV a bit mask of reversed outputs (bit n - 1)
PX4_SERVO_FUNCTION = 201  # output function of control surface 0 ("Servo 1")
PX4_MOTOR_FUNCTION = 101  # output function of motor 1, the throttle of a single-engine airplane
PX4_OUTPUTS = 16  # actuator_outputs' outputs
# CA_SV_CS{i}_TYPE -> flightid control (1 left aileron, 2 right aileron, 3 elevator,
# 4 rudder); a right aileron is read only when no left aileron is set
PX4_SURFACE_TYPES = {1: "da", 2: "da", 3: "de", 4: "dr"}
PX4_RIGHT_AILERON = 2
# A control surface's torque per unit of its actuator value (-1..1) is CA_SV_CS{i}_TRQ_R,
# _P, _Y (roll, pitch, yaw; PX4's control allocator). QGroundControl sets them from the
# type: left aileron roll -0.5, right aileron roll +0.5, elevator pitch +1, rudder yaw +1.
# A positive torque is a right roll, nose up, nose right; flightid's positive deflections
# give negative moments (channels.py, Etkin), so a surface's deflection has the opposite
# sign of its torque parameter: a left aileron's positive value is a positive da, a right
# aileron's, an elevator's and a rudder's a negative one
PX4_TORQUE_AXIS = {"da": "R", "de": "P", "dr": "Y"}
PX4_DEFAULT_TORQUE = {1: -0.5, 2: 0.5, 3: 1.0, 4: 1.0}
