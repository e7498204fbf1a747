/* A program compiled against the installed core with other settings than
 * the library's (install_consumer.sh passes e.g. -DQRT_GRID_DEG_MIN=10
 * -DQRT_MAX_POINTS=1024): its struct qrt_planner is smaller than the one the
 * library fills, so qrt_planner_init must refuse it with QRT_E_ABI, before
 * writing into it, rather than let the library run past its end. Prints
 * the library's sentence on the difference; exits 0 only when refused. */
#include <stdio.h>

#include "qrtplan/qrtplan.h"

static struct qrt_planner pl;

int main(void)
{
    char why[QRT_ABI_MESSAGE_LEN];
    struct qrt_params prm;
    int rc;
    qrt_params_default(&prm);
    rc = qrt_planner_init(&pl, &prm);
    if (rc != QRT_E_ABI) {
        printf("qrt_planner_init returned %d (%s), not QRT_E_ABI\n", rc,
               qrt_err_name(rc));
        return 1;
    }
    printf("%s\n", qrt_abi_message(why, sizeof why));
    return 0;
}
