package lcmloc.spy;

/**
 * The two-sided 95 % band of a chi-square variable, per degree of freedom: the 2.5 % and 97.5 %
 * quantiles. A consistent filter's NIS (tau = v' S^-1 v) of a dim-d innovation follows chi-square
 * with d degrees of freedom, so about 95 % of the strip's points lie inside the band.
 *
 * <p>The quantiles are a table (from the chi-square distribution; checked against its closed-form
 * CDF by the model test) rather than computed: the innovations of lcmloc's sensors have 1 to 3
 * dimensions, the table covers 1 to 6, and lcm-spy's CLASSPATH then needs no statistics jar.
 */
public final class Chi2Band {
    private static final double[] LOW = {
        0.000982069, 0.0506356, 0.215795, 0.484419, 0.831212, 1.237344,
    };
    private static final double[] HIGH = {
        5.023886, 7.377759, 9.348404, 11.143287, 12.832502, 14.449375,
    };

    private Chi2Band() {}

    /** Largest degree of freedom the table holds. */
    public static int maxDof() { return LOW.length; }

    /** True when the table holds a band for dof. */
    public static boolean has(int dof) { return dof >= 1 && dof <= LOW.length; }

    /** 2.5 % quantile of chi-square with dof degrees of freedom. */
    public static double low(int dof) { return LOW[index(dof)]; }

    /** 97.5 % quantile of chi-square with dof degrees of freedom. */
    public static double high(int dof) { return HIGH[index(dof)]; }

    private static int index(int dof) {
        if (!has(dof)) {
            throw new IllegalArgumentException(
                "no chi-square band for dof " + dof + " (the table holds 1.." + LOW.length + ")");
        }
        return dof - 1;
    }
}
