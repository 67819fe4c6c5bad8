"""The ArduPilot DataFlash messages flightid writes and reads, as ArduPilot's
``LogStructure.h`` defines them (ArduPlane 4.x): name, format characters, columns, unit
ids and multiplier ids (the FMTU metadata), and the unit and multiplier tables.

Format characters (ArduPilot): Q uint64, B uint8, b int8, H uint16, h int16, I uint32,
i int32, f float32, d float64, n char[4], N char[16], Z char[64], c int16 * 100,
C uint16 * 100, e int32 * 100, L int32 latitude/longitude * 1e7.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class LogFormat:
    """One DataFlash message type: id, name (at most 4 characters), format characters,
    comma-separated columns, unit ids and multiplier ids (one per column)."""

    type_id: int
    name: str
    format: str
    columns: str
    units: str
    mults: str


FMT_ID = 128  # the FMT message describes itself with this id in every DataFlash log
RCOU_OUTPUTS = 14
FORMATS: tuple[LogFormat, ...] = (
    LogFormat(129, "UNIT", "QbZ", "TimeUS,Id,Label", "s--", "F--"),
    LogFormat(130, "MULT", "Qbd", "TimeUS,Id,Mult", "s--", "F--"),
    LogFormat(131, "FMTU", "QBNN", "TimeUS,FmtType,UnitIds,MultIds", "s---", "F---"),
    LogFormat(132, "PARM", "QNff", "TimeUS,Name,Value,Default", "s---", "F---"),
    LogFormat(133, "MSG", "QZ", "TimeUS,Message", "s-", "F-"),
    LogFormat(134, "IMU", "QBffffffIIfBBHH",
              "TimeUS,I,GyrX,GyrY,GyrZ,AccX,AccY,AccZ,EG,EA,T,GH,AH,GHz,AHz",
              "s#EEEooo--O--zz", "F-000000-----00"),
    LogFormat(135, "ATT", "QccccCCCCB",
              "TimeUS,DesRoll,Roll,DesPitch,Pitch,DesYaw,Yaw,ErrRP,ErrYaw,AEKF",
              "sddddhhdh-", "FBBBBBBBB-"),
    LogFormat(136, "AOA", "Qff", "TimeUS,AOA,SSA", "sdd", "F00"),
    LogFormat(137, "ARSP", "QBffcff", "TimeUS,I,Airspeed,DiffPress,Temp,RawPress,Offset",
              "s#nPOPP", "F-00B00"),
    LogFormat(138, "CTUN", "Qcccchhhf",
              "TimeUS,NavRoll,Roll,NavPitch,Pitch,ThrOut,RdrOut,ThrDem,Aspd",
              "sdddd---n", "FBBBB---0"),
    LogFormat(139, "RCOU", "Q" + "H" * RCOU_OUTPUTS,
              "TimeUS," + ",".join(f"C{i}" for i in range(1, RCOU_OUTPUTS + 1)),
              "s" + "Y" * RCOU_OUTPUTS, "F" + "-" * RCOU_OUTPUTS),
    LogFormat(140, "GPS", "QBBIHBcLLeffffB",
              "TimeUS,I,Status,GMS,GWk,NSats,HDop,Lat,Lng,Alt,Spd,GCrs,VZ,Yaw,U",
              "s#-s-S-DUmnhnh-", "F--C--BGGB000--"),
    LogFormat(141, "BARO", "QBffcfIffB",
              "TimeUS,I,Alt,Press,Temp,CRt,SMS,Offset,GndTemp,Health",
              "s#mPOnsmO-", "F-00B0C00-"),
    # ArduPilot's system-identification mode: SIDS once when a chirp starts, SIDD each
    # logged sample during it
    LogFormat(142, "SIDS", "QBfffffff", "TimeUS,Ax,Mag,FSt,FSp,TFin,TC,TR,TFout",
              "s--zzssss", "F--------"),
    LogFormat(143, "SIDD", "Qfffffffff", "TimeUS,Time,Targ,F,Gx,Gy,Gz,Ax,Ay,Az",
              "ss-zkkkooo", "F---------"),
)
BY_NAME = {f.name: f for f in FORMATS}

# ArduPilot's log_Units and log_Multipliers entries used above
UNITS: dict[str, str] = {
    "-": "", "#": "instance", "s": "s", "E": "rad/s", "o": "m/s/s", "O": "degC",
    "z": "Hz", "d": "deg", "h": "degheading", "n": "m/s", "P": "Pa", "Y": "PWM",
    "D": "deglatitude", "U": "deglongitude", "m": "m", "S": "satellites",
}
MULTS: dict[str, float] = {"-": 0.0, "0": 1.0, "B": 1e-2, "C": 1e-3, "F": 1e-6, "G": 1e-7}

# ArduPilot SERVOn_FUNCTION values of the controls (SRV_Channel.h: k_flap 2, k_aileron 4,
# k_elevator 19, k_rudder 21, k_throttle 70)
SERVO_FUNCTIONS: dict[str, int] = {"da": 4, "de": 19, "throttle": 70, "dr": 21, "df": 2}
# The sign, in flightid's deflections (channels.py: Etkin's, a positive deflection gives a
# negative moment), of a servo output above its trim on an output not reversed. ArduPilot's
# scaled outputs are moment demands: a positive aileron, elevator or rudder output asks for
# a right roll, nose up or nose right (SRV_Channel's k_aileron, k_elevator, k_rudder, as the
# roll, pitch and yaw controllers write them), so it is a negative da, de, dr; a positive
# flap output lowers the flaps (df > 0)
SERVO_DEFLECTION_SIGN: dict[str, float] = {"da": -1.0, "de": -1.0, "dr": -1.0, "df": 1.0}

# ArduPilot's SystemId AxisType (SID_AXIS) -> the control it excites
SYSID_AXES: dict[int, str] = {
    1: "da", 4: "da", 7: "da", 10: "da", 20: "da", 22: "da",  # roll
    2: "de", 5: "de", 8: "de", 11: "de", 21: "de", 23: "de",  # pitch
    3: "dr", 6: "dr", 9: "dr", 12: "dr",  # yaw
    13: "throttle",
}
