/* Must be refused by tools/stack_report.py: recursion, a VLA, and an
 * indirect call it does not know. */
int qrt_fact(int n)
{
    return n <= 1 ? 1 : n * qrt_fact(n - 1);
}

int qrt_vla(int n)
{
    volatile char buf[n > 0 ? n : 1];
    buf[0] = 1;
    return buf[0];
}

int qrt_indirect(int (*f)(int), int x)
{
    return f(x);
}
