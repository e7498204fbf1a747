/* The ABI guard (planner.h, struct qrt_abi): the caller's build against
 * the library's, and the sentence that names where they differ. Written
 * into the caller's buffer, without allocation or stdio. */
#include <stddef.h>

#include "qrtplan/planner.h"

/* The sentence being written: msg is NULL when only the verdict is
 * wanted; at is where the next character goes, always below len. */
struct abi_text {
    char *msg;
    size_t len, at;
    int differences;
};

/* Append text, cut short where msg is full; msg stays terminated. */
static void put_text(struct abi_text *t, const char *text)
{
    size_t i = 0;
    if (t->msg == NULL)
        return;
    while (text[i] != '\0' && t->at + 1u < t->len) {
        t->msg[t->at] = text[i];
        t->at++;
        i++;
    }
    t->msg[t->at] = '\0';
}

/* Append a number in decimal. */
static void put_long(struct abi_text *t, long value)
{
    char digits[24]; /* 20 digits of a 64-bit long, sign, zero */
    size_t n = sizeof digits - 1u;
    /* the magnitude as unsigned: -LONG_MIN does not fit a long */
    unsigned long u =
        value < 0 ? 0UL - (unsigned long)value : (unsigned long)value;
    digits[n] = '\0';
    do {
        n--;
        digits[n] = (char)('0' + (int)(u % 10UL));
        u /= 10UL;
    } while (u > 0UL);
    if (value < 0) {
        n--;
        digits[n] = '-';
    }
    put_text(t, &digits[n]);
}

/* One setting or size: when the two builds differ in it, say so. */
static void compare(struct abi_text *t, const char *name, long caller,
                    long library)
{
    if (caller == library)
        return;
    put_text(t, t->differences == 0 ? "the caller was built with " : "; with ");
    put_text(t, name);
    put_text(t, " ");
    put_long(t, caller);
    put_text(t, ", the library with ");
    put_long(t, library);
    t->differences++;
}

int qrt_abi_check(const struct qrt_abi *caller, char *msg, size_t msg_len)
{
    struct qrt_abi lib = qrt_abi_here();
    struct abi_text t;
    t.msg = msg_len > 0u ? msg : NULL;
    /* every sentence fits QRT_ABI_MESSAGE_LEN (test_planner.c checks the
     * longest), so no more of a larger buffer is ever written */
    t.len = msg_len < QRT_ABI_MESSAGE_LEN ? msg_len : QRT_ABI_MESSAGE_LEN;
    t.at = 0;
    t.differences = 0;
    put_text(&t, "");
    /* the record's own size first and alone: a record from another
     * version's headers may be shorter than this one, and its other
     * fields are not read */
    compare(&t, "sizeof(struct qrt_abi)", caller->abi_bytes, lib.abi_bytes);
    if (t.differences > 0) {
        put_text(&t, " (headers of another qrtplan version)");
        return QRT_E_ABI;
    }
    compare(&t, "QRT_GRID_DEG_MIN", caller->grid_deg_min, lib.grid_deg_min);
    compare(&t, "QRT_MAX_POINTS", caller->max_points, lib.max_points);
    compare(&t, "QRT_MAX_WAYPOINTS", caller->max_waypoints, lib.max_waypoints);
    compare(&t, "QRT_GOAL_REGION_NODES", caller->goal_region_nodes,
            lib.goal_region_nodes);
    compare(&t, "QRT_LAZY_INDEX_AFTER", caller->lazy_index_after,
            lib.lazy_index_after);
    if (t.differences > 0)
        return QRT_E_ABI;
    /* the same settings laid out differently: only then are sizes news */
    compare(&t, "sizeof(struct qrt_planner)", caller->planner_bytes,
            lib.planner_bytes);
    compare(&t, "sizeof(struct qrt_plan)", caller->plan_bytes, lib.plan_bytes);
    compare(&t, "sizeof(struct qrt_target)", caller->target_bytes,
            lib.target_bytes);
    compare(&t, "sizeof(enum qrt_plan_status)", caller->enum_bytes,
            lib.enum_bytes);
    if (t.differences > 0) {
        put_text(&t, " (the same settings: another compiler or ABI option)");
        return QRT_E_ABI;
    }
    return QRT_OK;
}
