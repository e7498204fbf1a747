/* qrtplan: real-time path planning for a 3-DoF arm among range points. */
#ifndef QRTPLAN_QRTPLAN_H
#define QRTPLAN_QRTPLAN_H

#include "qrtplan/arm.h"
#include "qrtplan/config.h"
#include "qrtplan/lattice.h"
#include "qrtplan/params.h"
#include "qrtplan/planner.h"
#include "qrtplan/points.h"
#include "qrtplan/status.h"

#define QRTPLAN_VERSION "0.1.0"

#endif
