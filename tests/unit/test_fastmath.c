/* The raster's fast atan2 stays within the error bound it declares. */
#include "../../src/core/fastmath.h"
#include "check.h"

int main(void)
{
    double worst = 0.0;
    int i;
    test_seed(5);
    for (i = 0; i < test_count(2000000); i++) {
        double y = test_uniform(-1, 1), x = test_uniform(-1, 1);
        double e = fabs(qrt_fast_atan2(y, x) - atan2(y, x));
        if (e > worst)
            worst = e;
    }
    for (i = 0; i <= 100000; i++) { /* the whole unit circle, finely */
        double t = -QRT_PI + 2.0 * QRT_PI * i / 100000.0;
        double e = fabs(qrt_fast_atan2(sin(t), cos(t)) - atan2(sin(t), cos(t)));
        if (e > worst && fabs(fabs(t) - QRT_PI) > 1e-9)
            worst = e;
    }
    printf("worst fast atan2 error %.3g rad (bound %.3g)\n", worst,
           QRT_FAST_ANGLE_ERR);
    CHECK(worst <= QRT_FAST_ANGLE_ERR, "error %g over bound", worst);
    CHECK(qrt_fast_atan2(0.0, 0.0) == 0.0, "atan2(0, 0)");
    CHECK(fabs(qrt_fast_atan2(1.0, 0.0) - QRT_PI / 2) < 1e-12, "pi/2");
    return test_done("test_fastmath");
}
