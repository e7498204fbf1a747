/* Unit tests of the qrtcan codec: every encoder round-trips through its
 * decoder, known frames from CiA 301/402 decode as the standard says, and
 * a million random frames through every decoder give an error code or a
 * result that re-encodes to the same frame, never a crash. */
#include <stdio.h>
#include <string.h>

#include "qrtcan/qrtcan.h"

static int failures;

#define CHECK(cond)                                                            \
    do {                                                                       \
        if (!(cond)) {                                                         \
            fprintf(stderr, "%s:%d: CHECK(%s) failed\n", __FILE__, __LINE__,   \
                    #cond);                                                    \
            failures++;                                                        \
        }                                                                      \
    } while (0)

static struct qrtcan_frame frame(uint32_t id, uint8_t dlc, const char *hex)
{
    struct qrtcan_frame f;
    unsigned i, b;
    memset(&f, 0, sizeof f);
    f.id = id;
    f.dlc = dlc;
    for (i = 0; i < 8 && hex[2 * i] != 0; i++) {
        sscanf(&hex[2 * i], "%2x", &b);
        f.data[i] = (uint8_t)b;
    }
    return f;
}

static int same(const struct qrtcan_frame *a, const struct qrtcan_frame *b)
{
    return a->id == b->id && a->dlc == b->dlc &&
           memcmp(a->data, b->data, a->dlc) == 0;
}

static void test_nmt_sync_heartbeat(void)
{
    struct qrtcan_frame f;
    enum qrtcan_nmt_cmd cmd;
    enum qrtcan_nmt_state st;
    unsigned node, c;

    CHECK(qrtcan_nmt_encode(QRTCAN_NMT_START, 3, &f) == QRTCAN_OK);
    CHECK(f.id == 0 && f.dlc == 2 && f.data[0] == 1 && f.data[1] == 3);
    CHECK(qrtcan_nmt_decode(&f, &cmd, &node) == QRTCAN_OK);
    CHECK(cmd == QRTCAN_NMT_START && node == 3);
    CHECK(qrtcan_nmt_encode(QRTCAN_NMT_RESET_NODE, 0, &f) == QRTCAN_OK);
    CHECK(qrtcan_nmt_decode(&f, &cmd, &node) == QRTCAN_OK && node == 0);
    CHECK(qrtcan_nmt_addressed_to(0, 5) && qrtcan_nmt_addressed_to(5, 5) &&
          !qrtcan_nmt_addressed_to(4, 5));
    CHECK(qrtcan_nmt_encode(QRTCAN_NMT_START, 128, &f) == QRTCAN_E_NODE);
    CHECK(qrtcan_nmt_encode((enum qrtcan_nmt_cmd)3, 1, &f) == QRTCAN_E_ARG);
    f = frame(0, 2, "0301");
    CHECK(qrtcan_nmt_decode(&f, &cmd, &node) == QRTCAN_E_CMD);
    f = frame(0, 1, "01");
    CHECK(qrtcan_nmt_decode(&f, &cmd, &node) == QRTCAN_E_DLC);
    f = frame(0, 2, "0180");
    CHECK(qrtcan_nmt_decode(&f, &cmd, &node) == QRTCAN_E_NODE);
    f = frame(1, 2, "0101");
    CHECK(qrtcan_nmt_decode(&f, &cmd, &node) == QRTCAN_E_ID);

    CHECK(qrtcan_sync_encode(0, &f) == QRTCAN_OK && f.id == 0x80 && f.dlc == 0);
    CHECK(qrtcan_sync_decode(&f, &c) == QRTCAN_OK && c == 0);
    CHECK(qrtcan_sync_encode(17, &f) == QRTCAN_OK && f.dlc == 1);
    CHECK(qrtcan_sync_decode(&f, &c) == QRTCAN_OK && c == 17);
    CHECK(qrtcan_sync_encode(241, &f) == QRTCAN_E_ARG);
    f = frame(0x80, 1, "00");
    CHECK(qrtcan_sync_decode(&f, &c) == QRTCAN_E_RANGE);
    f = frame(0x80, 2, "0101");
    CHECK(qrtcan_sync_decode(&f, &c) == QRTCAN_E_DLC);
    f = frame(0x81, 0, "");
    CHECK(qrtcan_sync_decode(&f, &c) == QRTCAN_E_ID);

    CHECK(qrtcan_heartbeat_encode(2, QRTCAN_NMT_OPERATIONAL, &f) == QRTCAN_OK);
    CHECK(f.id == 0x702 && f.dlc == 1 && f.data[0] == 5);
    CHECK(qrtcan_heartbeat_decode(&f, &node, &st) == QRTCAN_OK);
    CHECK(node == 2 && st == QRTCAN_NMT_OPERATIONAL);
    f = frame(0x77F, 1, "FF"); /* pre-operational with the toggle bit set */
    CHECK(qrtcan_heartbeat_decode(&f, &node, &st) == QRTCAN_OK);
    CHECK(node == 127 && st == QRTCAN_NMT_PRE_OP);
    f = frame(0x701, 1, "06");
    CHECK(qrtcan_heartbeat_decode(&f, &node, &st) == QRTCAN_E_CMD);
    f = frame(0x700, 1, "00");
    CHECK(qrtcan_heartbeat_decode(&f, &node, &st) == QRTCAN_E_ID);
    f = frame(0x701, 2, "0000");
    CHECK(qrtcan_heartbeat_decode(&f, &node, &st) == QRTCAN_E_DLC);
}

static void test_emcy(void)
{
    struct qrtcan_frame f;
    struct qrtcan_emcy e = {QRTCAN_EMCY_HEARTBEAT, 0x11, {1, 2, 3, 4, 5}}, d;
    unsigned node;
    CHECK(qrtcan_emcy_encode(3, &e, &f) == QRTCAN_OK);
    CHECK(f.id == 0x83 && f.dlc == 8 && f.data[0] == 0x30 &&
          f.data[1] == 0x81 && f.data[2] == 0x11 && f.data[7] == 5);
    CHECK(qrtcan_emcy_decode(&f, &node, &d) == QRTCAN_OK);
    CHECK(node == 3 && d.code == e.code && d.error_register == 0x11 &&
          memcmp(d.vendor, e.vendor, 5) == 0);
    f.id = 0x80; /* SYNC is not an emergency */
    CHECK(qrtcan_emcy_decode(&f, &node, &d) == QRTCAN_E_ID);
    f.id = 0x83;
    f.dlc = 7;
    CHECK(qrtcan_emcy_decode(&f, &node, &d) == QRTCAN_E_DLC);
    CHECK(qrtcan_emcy_encode(0, &e, &f) == QRTCAN_E_NODE);
}

static void test_sdo(void)
{
    struct qrtcan_frame f, g;
    struct qrtcan_sdo s, d;
    unsigned node, size;

    /* client read of 0x6041:00 on node 1 */
    memset(&s, 0, sizeof s);
    s.type = QRTCAN_SDO_READ;
    s.index = 0x6041;
    CHECK(qrtcan_sdo_encode_request(1, &s, &f) == QRTCAN_OK);
    g = frame(0x601, 8, "4041600000000000");
    CHECK(same(&f, &g));
    CHECK(qrtcan_sdo_decode_request(&f, &node, &d) == QRTCAN_OK);
    CHECK(node == 1 && d.type == QRTCAN_SDO_READ && d.index == 0x6041 &&
          d.subindex == 0);

    /* writes of every size, as a client and as a server sees them */
    for (size = 0; size <= 4; size++) {
        s.type = QRTCAN_SDO_WRITE;
        s.index = 0x607A;
        s.subindex = 0;
        s.size = (uint8_t)size;
        s.data = 0xA1B2C3D4u;
        CHECK(qrtcan_sdo_encode_request(5, &s, &f) == QRTCAN_OK);
        CHECK(qrtcan_sdo_decode_request(&f, &node, &d) == QRTCAN_OK);
        CHECK(node == 5 && d.type == QRTCAN_SDO_WRITE && d.size == size);
        CHECK(d.data == (size == 0 || size == 4
                             ? 0xA1B2C3D4u
                             : (0xA1B2C3D4u & ((1u << (8 * size)) - 1u))));
        s.type = QRTCAN_SDO_READ_OK;
        CHECK(qrtcan_sdo_encode_response(5, &s, &f) == QRTCAN_OK);
        CHECK(f.id == 0x585);
        CHECK(qrtcan_sdo_decode_response(&f, &node, &d) == QRTCAN_OK);
        CHECK(d.type == QRTCAN_SDO_READ_OK && d.size == size);
    }
    /* a 16-bit write of 0x000F to 0x6040 is 2B 40 60 00 0F 00 00 00 */
    s.type = QRTCAN_SDO_WRITE;
    s.index = 0x6040;
    s.size = 2;
    s.data = 0x0F;
    CHECK(qrtcan_sdo_encode_request(2, &s, &f) == QRTCAN_OK);
    g = frame(0x602, 8, "2B4060000F000000");
    CHECK(same(&f, &g));
    /* server answers: 0x6064 = -1000 as i32, a download ack, an abort */
    g = frame(0x582, 8, "4364600018FCFFFF");
    CHECK(qrtcan_sdo_decode_response(&g, &node, &d) == QRTCAN_OK);
    CHECK(d.type == QRTCAN_SDO_READ_OK && d.size == 4 &&
          qrtcan_sdo_signed(&d) == -1000);
    g = frame(0x582, 8, "4F60600001000000");
    CHECK(qrtcan_sdo_decode_response(&g, &node, &d) == QRTCAN_OK);
    CHECK(d.size == 1 && qrtcan_sdo_signed(&d) == 1);
    g = frame(0x582, 8, "4F606000FF000000");
    CHECK(qrtcan_sdo_decode_response(&g, &node, &d) == QRTCAN_OK);
    CHECK(qrtcan_sdo_signed(&d) == -1);
    g = frame(0x582, 8, "6040600000000000");
    CHECK(qrtcan_sdo_decode_response(&g, &node, &d) == QRTCAN_OK);
    CHECK(d.type == QRTCAN_SDO_WRITE_OK && d.index == 0x6040);
    s.type = QRTCAN_SDO_ABORT;
    s.index = 0x1234;
    s.subindex = 7;
    s.data = QRTCAN_SDO_ABORT_NO_OBJECT;
    CHECK(qrtcan_sdo_encode_response(2, &s, &f) == QRTCAN_OK);
    g = frame(0x582, 8, "8034120700000206");
    CHECK(same(&f, &g));
    CHECK(qrtcan_sdo_decode_response(&f, &node, &d) == QRTCAN_OK);
    CHECK(d.type == QRTCAN_SDO_ABORT && d.data == QRTCAN_SDO_ABORT_NO_OBJECT);

    /* what an expedited-only codec must refuse, naming the object */
    g = frame(0x602, 8, "2108100000000000"); /* segmented download */
    CHECK(qrtcan_sdo_decode_request(&g, &node, &d) == QRTCAN_E_UNSUPP);
    CHECK(d.index == 0x1008 && d.subindex == 0);
    g = frame(0x602, 8, "C000000000000000"); /* block upload */
    CHECK(qrtcan_sdo_decode_request(&g, &node, &d) == QRTCAN_E_UNSUPP);
    g = frame(0x602, 8, "E000000000000000");
    CHECK(qrtcan_sdo_decode_request(&g, &node, &d) == QRTCAN_E_CMD);
    g = frame(0x582, 8, "4108100000000000"); /* segmented upload reply */
    CHECK(qrtcan_sdo_decode_response(&g, &node, &d) == QRTCAN_E_UNSUPP);
    g = frame(0x602, 7, "40416000000000");
    CHECK(qrtcan_sdo_decode_request(&g, &node, &d) == QRTCAN_E_DLC);
    g = frame(0x600, 8, "4041600000000000");
    CHECK(qrtcan_sdo_decode_request(&g, &node, &d) == QRTCAN_E_ID);
    g = frame(0x582, 8, "4041600000000000");
    CHECK(qrtcan_sdo_decode_request(&g, &node, &d) == QRTCAN_E_ID);
    /* role checks: a client does not send READ_OK, a server not WRITE */
    s.type = QRTCAN_SDO_READ_OK;
    CHECK(qrtcan_sdo_encode_request(2, &s, &f) == QRTCAN_E_ARG);
    s.type = QRTCAN_SDO_WRITE;
    CHECK(qrtcan_sdo_encode_response(2, &s, &f) == QRTCAN_E_ARG);
    s.size = 5;
    CHECK(qrtcan_sdo_encode_request(2, &s, &f) == QRTCAN_E_ARG);
}

static void test_cia402(void)
{
    static const enum qrtcan_402_state all[] = {
        QRTCAN_402_NOT_READY_TO_SWITCH_ON, QRTCAN_402_SWITCH_ON_DISABLED,
        QRTCAN_402_READY_TO_SWITCH_ON,     QRTCAN_402_SWITCHED_ON,
        QRTCAN_402_OPERATION_ENABLED,      QRTCAN_402_QUICK_STOP_ACTIVE,
        QRTCAN_402_FAULT_REACTION_ACTIVE,  QRTCAN_402_FAULT};
    struct qrtcan_frame f;
    struct qrtcan_402_rpdo r = {0x001F, -123456}, rd;
    struct qrtcan_402_tpdo t = {0x1637, 2147483647}, td;
    enum qrtcan_402_state st;
    unsigned i, node, cw, steps;
    uint16_t prev;

    for (i = 0; i < sizeof all / sizeof all[0]; i++) {
        /* every statusword the drive sends decodes to its state, with any
         * of the other bits set */
        uint16_t sw = qrtcan_402_statusword_bits(all[i]);
        CHECK(qrtcan_402_state_from_statusword(sw) == all[i]);
        CHECK(qrtcan_402_state_from_statusword((uint16_t)(sw | 0xFE80u)) ==
              all[i]);
    }
    /* typical statuswords of real drives */
    CHECK(qrtcan_402_state_from_statusword(0x0250) ==
          QRTCAN_402_SWITCH_ON_DISABLED);
    CHECK(qrtcan_402_state_from_statusword(0x0237) ==
          QRTCAN_402_OPERATION_ENABLED);
    CHECK(qrtcan_402_state_from_statusword(0x0217) ==
          QRTCAN_402_QUICK_STOP_ACTIVE);
    CHECK(qrtcan_402_state_from_statusword(0x0218) == QRTCAN_402_FAULT);
    CHECK(qrtcan_402_state_from_statusword(0x0029) == QRTCAN_402_UNKNOWN);

    CHECK(qrtcan_402_command(0, 0x06) == QRTCAN_402_CMD_SHUTDOWN);
    CHECK(qrtcan_402_command(0, 0x0E) == QRTCAN_402_CMD_SHUTDOWN);
    CHECK(qrtcan_402_command(0, 0x07) == QRTCAN_402_CMD_SWITCH_ON);
    CHECK(qrtcan_402_command(0, 0x1F) == QRTCAN_402_CMD_ENABLE_OPERATION);
    CHECK(qrtcan_402_command(0, 0x00) == QRTCAN_402_CMD_DISABLE_VOLTAGE);
    CHECK(qrtcan_402_command(0, 0x0D) == QRTCAN_402_CMD_DISABLE_VOLTAGE);
    CHECK(qrtcan_402_command(0, 0x02) == QRTCAN_402_CMD_QUICK_STOP);
    CHECK(qrtcan_402_command(0, 0x0B) == QRTCAN_402_CMD_QUICK_STOP);
    CHECK(qrtcan_402_command(0x00, 0x80) == QRTCAN_402_CMD_FAULT_RESET);
    CHECK(qrtcan_402_command(0x80, 0x80) == QRTCAN_402_CMD_DISABLE_VOLTAGE);

    /* the master's controlwords bring a drive from any state to Operation
     * Enabled, stepping it with the drive's own transition function */
    for (i = 0; i < sizeof all / sizeof all[0]; i++) {
        st = all[i];
        if (st == QRTCAN_402_NOT_READY_TO_SWITCH_ON ||
            st == QRTCAN_402_FAULT_REACTION_ACTIVE) {
            continue; /* the drive leaves these by itself */
        }
        prev = 0x80; /* the worst case: bit 7 left high */
        for (steps = 0; steps < 8 && st != QRTCAN_402_OPERATION_ENABLED;
             steps++) {
            cw = qrtcan_402_controlword_toward(st, QRTCAN_402_OPERATION_ENABLED,
                                               prev);
            st = qrtcan_402_transition(st,
                                       qrtcan_402_command(prev, (uint16_t)cw));
            prev = (uint16_t)cw;
        }
        CHECK(st == QRTCAN_402_OPERATION_ENABLED);
        CHECK(steps <= 5);
        /* and back down to Switch On Disabled */
        cw = qrtcan_402_controlword_toward(st, QRTCAN_402_SWITCH_ON_DISABLED,
                                           prev);
        CHECK(
            qrtcan_402_transition(st, qrtcan_402_command(prev, (uint16_t)cw)) ==
            QRTCAN_402_SWITCH_ON_DISABLED);
    }
    CHECK(qrtcan_402_transition(QRTCAN_402_OPERATION_ENABLED,
                                QRTCAN_402_CMD_QUICK_STOP) ==
          QRTCAN_402_QUICK_STOP_ACTIVE);
    CHECK(qrtcan_402_transition(QRTCAN_402_FAULT,
                                QRTCAN_402_CMD_ENABLE_OPERATION) ==
          QRTCAN_402_FAULT);
    CHECK(qrtcan_402_transition(QRTCAN_402_SWITCH_ON_DISABLED,
                                QRTCAN_402_CMD_ENABLE_OPERATION) ==
          QRTCAN_402_SWITCH_ON_DISABLED);
    CHECK(strcmp(qrtcan_402_state_name(QRTCAN_402_FAULT), "FAULT") == 0);

    CHECK(qrtcan_402_rpdo_encode(2, &r, &f) == QRTCAN_OK);
    CHECK(f.id == 0x202 && f.dlc == 6 && f.data[0] == 0x1F &&
          f.data[2] == 0xC0 && f.data[5] == 0xFF);
    CHECK(qrtcan_402_rpdo_decode(&f, &node, &rd) == QRTCAN_OK);
    CHECK(node == 2 && rd.controlword == 0x1F && rd.target_position == -123456);
    CHECK(qrtcan_402_tpdo_decode(&f, &node, &td) == QRTCAN_E_ID);
    CHECK(qrtcan_402_tpdo_encode(127, &t, &f) == QRTCAN_OK && f.id == 0x1FF);
    CHECK(qrtcan_402_tpdo_decode(&f, &node, &td) == QRTCAN_OK);
    CHECK(td.statusword == 0x1637 && td.position_actual == 2147483647);
    t.position_actual = -2147483647 - 1;
    CHECK(qrtcan_402_tpdo_encode(1, &t, &f) == QRTCAN_OK);
    CHECK(qrtcan_402_tpdo_decode(&f, &node, &td) == QRTCAN_OK);
    CHECK(td.position_actual == -2147483647 - 1);
    f.dlc = 8;
    CHECK(qrtcan_402_tpdo_decode(&f, &node, &td) == QRTCAN_E_DLC);
    CHECK(qrtcan_402_tpdo_encode(0, &t, &f) == QRTCAN_E_NODE);
}

static void test_scale(void)
{
    struct qrtcan_scale s[3] = {
        {1000.0, 0}, {-4096.0 * 100 / 360, 500}, {0.5, -7}};
    double deg[3] = {-179.9996, 42.25, 139.0}, back[3], zero = 0.0;
    int32_t c[3];
    int i;
    CHECK(qrtcan_joints_to_counts(s, deg, c) == QRTCAN_OK);
    CHECK(c[0] == -180000); /* -179999.6 rounds half away from zero */
    CHECK(qrtcan_counts_to_joints(s, c, back) == QRTCAN_OK);
    for (i = 0; i < 3; i++) {
        double err = back[i] - deg[i];
        double tol = 0.5 / (s[i].counts_per_deg < 0 ? -s[i].counts_per_deg
                                                    : s[i].counts_per_deg);
        CHECK(err <= tol + 1e-12 && err >= -tol - 1e-12);
    }
    CHECK(qrtcan_deg_to_counts(&s[0], -2.5e-3, &c[0]) == QRTCAN_OK &&
          c[0] == -3);
    CHECK(qrtcan_deg_to_counts(&s[0], 2147483.6475, &c[0]) == QRTCAN_E_RANGE);
    CHECK(qrtcan_deg_to_counts(&s[0], 2147483.647, &c[0]) == QRTCAN_OK &&
          c[0] == 2147483647);
    CHECK(qrtcan_deg_to_counts(&s[0], -2147483.648, &c[0]) == QRTCAN_OK &&
          c[0] == -2147483647 - 1);
    CHECK(qrtcan_deg_to_counts(&s[0], zero / zero, &c[0]) == QRTCAN_E_RANGE);
    CHECK(qrtcan_deg_to_counts(&s[0], 1.0 / zero, &c[0]) == QRTCAN_E_RANGE);
    s[0].counts_per_deg = 0;
    CHECK(qrtcan_deg_to_counts(&s[0], 1.0, &c[0]) == QRTCAN_E_ARG);
    CHECK(qrtcan_counts_to_deg(&s[0], 1, &back[0]) == QRTCAN_E_ARG);
}

/* xorshift: the same garbage on every machine */
static uint32_t rnd(uint32_t *x)
{
    *x ^= *x << 13;
    *x ^= *x >> 17;
    *x ^= *x << 5;
    return *x;
}

static void test_node_list(void)
{
    static const char *const bad[] = {
        "",        "0",    "128",        "1,1",
        "1,,3",    "1,2,", ",1",         "+1",
        " 1",      "1 ",   "0x2",        "-1",
        "1,2,3,4", "1;2",  "4294967297", "99999999999999999999",
        "1,128",   "12a",
    };
    unsigned ids[4] = {0}, n = 99, i;
    CHECK(qrtcan_parse_node_list("1,2,3", ids, 3, &n) == QRTCAN_OK);
    CHECK(n == 3 && ids[0] == 1 && ids[1] == 2 && ids[2] == 3);
    CHECK(qrtcan_parse_node_list("127", ids, 3, &n) == QRTCAN_OK);
    CHECK(n == 1 && ids[0] == 127);
    CHECK(qrtcan_parse_node_list("007,10", ids, 3, &n) == QRTCAN_OK);
    CHECK(n == 2 && ids[0] == 7 && ids[1] == 10);
    CHECK(qrtcan_parse_node_list("4,3,2,1", ids, 4, &n) == QRTCAN_OK);
    CHECK(n == 4 && ids[0] == 4 && ids[3] == 1);
    for (i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        n = 99;
        if (qrtcan_parse_node_list(bad[i], ids, 3, &n) != QRTCAN_E_ARG ||
            n != 99) {
            fprintf(stderr, "node list \"%s\" taken\n", bad[i]);
            failures++;
        }
    }
    CHECK(qrtcan_parse_node_list(0, ids, 3, &n) == QRTCAN_E_ARG);
    CHECK(qrtcan_parse_node_list("1", ids, 0, &n) == QRTCAN_E_ARG);
}

static void test_garbage(void)
{
    uint32_t seed = 0x9E3779B9u;
    long n, accepted = 0;
    for (n = 0; n < 1000000; n++) {
        struct qrtcan_frame f, g;
        enum qrtcan_kind kind;
        enum qrtcan_nmt_cmd cmd;
        enum qrtcan_nmt_state st;
        struct qrtcan_emcy e;
        struct qrtcan_sdo s;
        struct qrtcan_402_rpdo r;
        struct qrtcan_402_tpdo t;
        unsigned node, c, i;
        uint32_t v = rnd(&seed);
        /* identifiers near the ones the codec knows, and any at all */
        f.id = (v & 1) ? (rnd(&seed) & 0xFFFFFFFFu)
                       : ((rnd(&seed) % 16) * 0x80u +
                          (rnd(&seed) % 4 == 0 ? 0 : rnd(&seed) % 0x80u));
        /* half the time a DLC some frame really has, else any nibble */
        f.dlc = (rnd(&seed) & 1) ? (uint8_t)("\0\1\2\6\10"[rnd(&seed) % 5])
                                 : (uint8_t)(rnd(&seed) % 16);
        for (i = 0; i < 8; i++) {
            f.data[i] = (uint8_t)rnd(&seed);
        }
        (void)qrtcan_classify(&f, &kind, &node);
        if (qrtcan_nmt_decode(&f, &cmd, &c) == QRTCAN_OK) {
            accepted++;
            CHECK(qrtcan_nmt_encode(cmd, c, &g) == QRTCAN_OK && same(&f, &g));
        }
        if (qrtcan_sync_decode(&f, &c) == QRTCAN_OK) {
            accepted++;
            CHECK(qrtcan_sync_encode(c, &g) == QRTCAN_OK && same(&f, &g));
        }
        if (qrtcan_heartbeat_decode(&f, &node, &st) == QRTCAN_OK) {
            accepted++;
            CHECK(qrtcan_heartbeat_encode(node, st, &g) == QRTCAN_OK);
            CHECK(g.id == f.id && (g.data[0] & 0x7F) == (f.data[0] & 0x7F));
        }
        if (qrtcan_emcy_decode(&f, &node, &e) == QRTCAN_OK) {
            accepted++;
            CHECK(qrtcan_emcy_encode(node, &e, &g) == QRTCAN_OK &&
                  same(&f, &g));
        }
        if (qrtcan_sdo_decode_request(&f, &node, &s) == QRTCAN_OK) {
            accepted++;
            CHECK(qrtcan_sdo_encode_request(node, &s, &g) == QRTCAN_OK);
            CHECK(g.id == f.id && memcmp(&g.data[1], &f.data[1], 3) == 0);
        }
        if (qrtcan_sdo_decode_response(&f, &node, &s) == QRTCAN_OK) {
            accepted++;
            CHECK(qrtcan_sdo_encode_response(node, &s, &g) == QRTCAN_OK);
            CHECK(g.id == f.id && memcmp(&g.data[1], &f.data[1], 3) == 0);
        }
        if (qrtcan_402_rpdo_decode(&f, &node, &r) == QRTCAN_OK) {
            accepted++;
            CHECK(qrtcan_402_rpdo_encode(node, &r, &g) == QRTCAN_OK &&
                  same(&f, &g));
        }
        if (qrtcan_402_tpdo_decode(&f, &node, &t) == QRTCAN_OK) {
            accepted++;
            CHECK(qrtcan_402_tpdo_encode(node, &t, &g) == QRTCAN_OK &&
                  same(&f, &g));
        }
    }
    printf("random frames accepted by a decoder: %ld\n", accepted);
    CHECK(accepted > 10000); /* the garbage reached past the DLC checks */
    /* NULL is refused, not dereferenced */
    CHECK(qrtcan_sdo_decode_request(0, 0, 0) == QRTCAN_E_ARG);
    CHECK(qrtcan_402_tpdo_decode(0, 0, 0) == QRTCAN_E_ARG);
    CHECK(qrtcan_classify(0, 0, 0) == QRTCAN_E_ARG);
}

int main(void)
{
    test_nmt_sync_heartbeat();
    test_emcy();
    test_sdo();
    test_cia402();
    test_scale();
    test_node_list();
    test_garbage();
    if (failures) {
        fprintf(stderr, "test_can_codec: %d checks failed\n", failures);
        return 1;
    }
    printf("test_can_codec: all checks passed\n");
    return 0;
}
