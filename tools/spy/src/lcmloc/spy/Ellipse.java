package lcmloc.spy;

/**
 * The k-sigma ellipse of a 2x2 position covariance [[sxx, sxy], [sxy, syy]]: semi-axes
 * k*sqrt(eigenvalue), the major axis at angle {@link #angle} from the x axis.
 */
public final class Ellipse {
    public final double major;
    public final double minor;
    public final double angle;

    private Ellipse(double major, double minor, double angle) {
        this.major = major;
        this.minor = minor;
        this.angle = angle;
    }

    /** The sigmas-sigma ellipse of the covariance; negative eigenvalues (round-off) count as 0. */
    public static Ellipse of(double sxx, double sxy, double syy, double sigmas) {
        double mean = 0.5 * (sxx + syy);
        double half = Math.hypot(0.5 * (sxx - syy), sxy);
        double l1 = Math.max(0.0, mean + half);
        double l2 = Math.max(0.0, mean - half);
        double angle = 0.5 * Math.atan2(2.0 * sxy, sxx - syy);
        return new Ellipse(sigmas * Math.sqrt(l1), sigmas * Math.sqrt(l2), angle);
    }

    /** This ellipse with both axes multiplied by factor. */
    public Ellipse scaled(double factor) {
        return new Ellipse(major * factor, minor * factor, angle);
    }

    /** n points (x0, y0, x1, y1, ...) on the ellipse centred at (cx, cy). */
    public double[] points(double cx, double cy, int n) {
        double[] xy = new double[2 * n];
        double c = Math.cos(angle);
        double s = Math.sin(angle);
        for (int i = 0; i < n; ++i) {
            double t = 2.0 * Math.PI * i / n;
            double a = major * Math.cos(t);
            double b = minor * Math.sin(t);
            xy[2 * i] = cx + c * a - s * b;
            xy[2 * i + 1] = cy + s * a + c * b;
        }
        return xy;
    }

    /**
     * The factor the ellipse is drawn with so that it is visible: 1 when its major semi-axis is at
     * least minFraction of the view's extent, else the smallest 1, 2, 5 x 10^k that makes it so.
     */
    public static double visibleScale(double major, double extent, double minFraction) {
        double need = minFraction * extent;
        if (!(major > 0.0) || major >= need) {
            return 1.0;
        }
        double ratio = need / major;
        double decade = Math.pow(10.0, Math.floor(Math.log10(ratio)));
        for (double step : new double[] {1.0, 2.0, 5.0, 10.0}) {
            if (step * decade >= ratio) {
                return step * decade;
            }
        }
        return 10.0 * decade;
    }
}
