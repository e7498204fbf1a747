/* Everything of the qrtcan CANopen / CiA 402 codec. */
#ifndef QRTCAN_QRTCAN_H
#define QRTCAN_QRTCAN_H

#include "qrtcan/cia402.h"
#include "qrtcan/emcy.h"
#include "qrtcan/frame.h"
#include "qrtcan/nmt.h"
#include "qrtcan/scale.h"
#include "qrtcan/sdo.h"
#include "qrtcan/sync.h"

#endif
