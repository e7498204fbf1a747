#include "qrtplan/status.h"

const char *qrt_plan_status_name(enum qrt_plan_status status)
{
    switch (status) {
    case QRT_STATUS_OK:
        return "ok";
    case QRT_STATUS_NO_PATH:
        return "no_path";
    case QRT_STATUS_START_BLOCKED:
        return "start_blocked";
    case QRT_STATUS_GOAL_BLOCKED:
        return "goal_blocked";
    case QRT_STATUS_UNREACHABLE:
        return "unreachable";
    case QRT_STATUS_CAPACITY:
        return "capacity";
    }
    return "unknown";
}

const char *qrt_err_name(int err)
{
    switch (err) {
    case QRT_OK:
        return "ok";
    case QRT_E_INVALID:
        return "invalid input (non-finite value, bad size or setting)";
    case QRT_E_LIMITS:
        return "joint configuration outside the arm's limits";
    case QRT_E_TOO_BIG:
        return "lattice larger than this build's tables";
    case QRT_E_ABI:
        return "caller compiled with other settings than the library "
               "(QRT_GRID_DEG_MIN, QRT_MAX_POINTS, ...: qrt_abi_message "
               "names them)";
    default:
        return "unknown error";
    }
}
