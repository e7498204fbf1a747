/* With twin_b.c: two units with a static function of the same name, which
 * tools/stack_report.py cannot tell apart and must refuse. */
__attribute__((noinline)) static int twin(int x)
{
    volatile char buf[64];
    buf[0] = (char)x;
    return buf[0];
}

int qrt_twin_a(int x)
{
    return twin(x) + 1;
}
