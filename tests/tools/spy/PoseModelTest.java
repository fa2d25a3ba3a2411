package lcmloc.spy;

import java.awt.image.BufferedImage;
import java.io.ByteArrayInputStream;
import java.io.ByteArrayOutputStream;
import java.io.DataInputStream;
import java.io.DataOutputStream;
import java.io.File;
import java.io.IOException;
import java.io.StringReader;
import java.nio.file.Paths;
import java.util.List;

import javax.imageio.ImageIO;

import lcmloc.gate_decision_t;
import lcmloc.pose_t;

/**
 * Headless test of the lcm-spy pose view: encoded pose_t and gate_decision_t messages go through
 * PoseModel.accept as lcm-spy's subscription hands them over; the ellipse, the ring bound, the
 * chi-square band, the map parser and a painted frame are checked.
 * Arguments: MAP_CSV [PNG_OUT] (the PNG is written when given).
 */
public final class PoseModelTest {
    private static int failures;
    private static int checks;

    private static void check(boolean ok, String what) {
        ++checks;
        if (!ok) {
            ++failures;
            System.out.println("FAIL: " + what);
        }
    }

    private static void near(double got, double want, double tol, String what) {
        check(Math.abs(got - want) <= tol, what + ": got " + got + ", want " + want + " +- " + tol);
    }

    static pose_t pose(long utime, double x, double y, double theta, double[][] cov) {
        pose_t p = new pose_t();
        p.utime = utime;
        p.seq = utime;
        p.filter = "ekf";
        p.status = pose_t.STATUS_OK;
        p.dim = 3;
        p.state = new double[] {x, y, theta};
        p.state_names = new String[] {"x", "y", "theta"};
        p.covariance = cov;
        return p;
    }

    static gate_decision_t gate(long utime, String filter, int dim, double nis, boolean accepted, int marker) {
        gate_decision_t g = new gate_decision_t();
        g.utime = utime;
        g.filter = filter;
        g.sensor = "MAGRULER";
        g.dim = dim;
        g.innovation = new double[dim];
        g.mahalanobis = nis;
        g.gate = 3.0;
        g.accepted = accepted;
        g.marker_id = marker;
        g.reason = accepted ? "accepted" : "gate";
        return g;
    }

    /** Encodes msg as on the wire and hands it to the model as the LCM subscription does. */
    static void feed(PoseModel model, String channel, Object msg) throws IOException {
        ByteArrayOutputStream bytes = new ByteArrayOutputStream();
        DataOutputStream out = new DataOutputStream(bytes);
        if (msg instanceof pose_t) {
            ((pose_t) msg).encode(out);
        } else {
            ((gate_decision_t) msg).encode(out);
        }
        model.accept(channel, new DataInputStream(new ByteArrayInputStream(bytes.toByteArray())));
    }

    static double[][] cov(double sxx, double sxy, double syy) {
        return new double[][] {{sxx, sxy, 0}, {sxy, syy, 0}, {0, 0, 0.01}};
    }

    static void ellipse() {
        Ellipse e = Ellipse.of(4.0, 0.0, 1.0, 3.0);
        near(e.major, 6.0, 1e-12, "3-sigma major of diag(4,1)");
        near(e.minor, 3.0, 1e-12, "3-sigma minor of diag(4,1)");
        near(e.angle, 0.0, 1e-12, "angle of diag(4,1)");
        // R(30 deg) diag(9, 1) R': 3-sigma semi-axes 9 and 3, major axis at 30 deg.
        double c = Math.cos(Math.PI / 6), s = Math.sin(Math.PI / 6);
        double sxx = 9 * c * c + s * s, sxy = (9 - 1) * c * s, syy = 9 * s * s + c * c;
        Ellipse r = Ellipse.of(sxx, sxy, syy, 3.0);
        near(r.major, 9.0, 1e-9, "3-sigma major of rotated covariance");
        near(r.minor, 3.0, 1e-9, "3-sigma minor of rotated covariance");
        near(r.angle, Math.PI / 6, 1e-9, "angle of rotated covariance");
        double det = sxx * syy - sxy * sxy;
        double[] xy = r.points(10.0, -5.0, 36);
        double worst = 0.0;
        for (int i = 0; i < 36; ++i) {
            double dx = xy[2 * i] - 10.0, dy = xy[2 * i + 1] + 5.0;
            double m = (syy * dx * dx - 2 * sxy * dx * dy + sxx * dy * dy) / det;
            worst = Math.max(worst, Math.abs(m - 9.0));
        }
        near(worst, 0.0, 1e-9, "every ellipse point at Mahalanobis distance 3");
        near(Ellipse.visibleScale(0.01, 100.0, 0.03), 500.0, 0, "scale making a 1 cm ellipse visible on 100 m");
        near(Ellipse.visibleScale(0.02, 100.0, 0.03), 200.0, 0, "scale for 2 cm on 100 m");
        near(Ellipse.visibleScale(5.0, 100.0, 0.03), 1.0, 0, "a visible ellipse is not scaled");
    }

    static double erf(double x) { // Abramowitz and Stegun 7.1.26, |error| < 1.5e-7
        double t = 1.0 / (1.0 + 0.3275911 * Math.abs(x));
        double y = 1 - t * (0.254829592 + t * (-0.284496736 + t * (1.421413741
            + t * (-1.453152027 + t * 1.061405429)))) * Math.exp(-x * x);
        return x >= 0 ? y : -y;
    }

    /** Closed-form chi-square CDF for dof 1..6. */
    static double chi2Cdf(double x, int dof) {
        double e = Math.exp(-x / 2), odd = erf(Math.sqrt(x / 2)), g = Math.sqrt(2 * x / Math.PI) * e;
        switch (dof) {
            case 1: return odd;
            case 2: return 1 - e;
            case 3: return odd - g;
            case 4: return 1 - e * (1 + x / 2);
            case 5: return odd - g * (1 + x / 3);
            case 6: return 1 - e * (1 + x / 2 + x * x / 8);
            default: throw new IllegalArgumentException("dof " + dof);
        }
    }

    static void band() {
        check(Chi2Band.maxDof() >= 3, "band table covers dof 1..3");
        for (int dof = 1; dof <= Chi2Band.maxDof(); ++dof) {
            near(chi2Cdf(Chi2Band.low(dof), dof), 0.025, 2e-6, "chi2 CDF at the low quantile, dof " + dof);
            near(chi2Cdf(Chi2Band.high(dof), dof), 0.975, 2e-6, "chi2 CDF at the high quantile, dof " + dof);
        }
        try {
            Chi2Band.high(Chi2Band.maxDof() + 1);
            check(false, "a dof beyond the table is refused");
        } catch (IllegalArgumentException expected) {
            check(expected.getMessage().contains("dof " + (Chi2Band.maxDof() + 1)), "refusal names the dof");
        }
    }

    static void model() throws IOException {
        PoseModel m = new PoseModel("GATE", 10, 4, 5);
        feed(m, "GATE", gate(1, "ekf", 2, 1.0, true, 7)); // before any pose: NIS only, no mark
        for (int i = 0; i < 25; ++i) {
            feed(m, "POSE", pose(1000 + i, i, 2.0 * i, 0.1, cov(0.25, 0.0, 0.04)));
        }
        PoseModel.Snapshot s = m.snapshot();
        check(s.track.size() == 10, "track ring bounded at 10, holds " + s.track.size());
        check(s.poses == 25, "25 poses counted, got " + s.poses);
        near(s.track.get(0).x, 15.0, 0, "oldest kept estimate is the 16th");
        near(s.last().y, 48.0, 0, "newest estimate y");
        near(s.covariance[0], 0.25, 0, "sxx from the encoded covariance");
        near(s.covariance[2], 0.04, 0, "syy from the encoded covariance");
        Ellipse e = Ellipse.of(s.covariance[0], s.covariance[1], s.covariance[2], 3.0);
        near(e.major, 1.5, 1e-12, "3-sigma major from the message");
        near(e.minor, 0.6, 1e-12, "3-sigma minor from the message");
        check(s.marks.isEmpty() && s.nis.size() == 1, "a decision before any pose is not placed on the map");

        feed(m, "GATE", gate(2000, "ekf", 2, 20.0, false, 3));
        feed(m, "GATE", gate(2001, "shadow_ukf", 2, 0.5, true, 3)); // another filter's decision
        feed(m, "GATE", gate(2002, "ekf", 1, 0.5, true, -1));
        feed(m, "GATE", gate(2003, "ekf", 3, 9.0, true, 4));
        feed(m, "GATE", gate(2004, "ekf", 3, 9.5, true, 4));
        s = m.snapshot();
        check(s.nis.size() == 5, "NIS strip bounded at 5 and the shadow filter's decision left out, holds " + s.nis.size());
        check(s.decisions == 4, "4 decisions placed, got " + s.decisions);
        check(s.marks.size() == 4, "mark ring bounded at 4");
        PoseModel.Mark rejected = s.marks.get(0);
        check(!rejected.accepted && rejected.markerId == 3, "first mark: the rejected decision on marker 3");
        near(rejected.x, 24.0, 0, "decision placed at the latest estimate");
        PoseModel.Nis big = s.nis.get(1);
        near(big.low, Chi2Band.low(2), 0, "band of a dim-2 innovation");
        check(!big.inBand() && !big.accepted, "NIS 20 of dim 2 is outside the band");
        check(s.nis.get(2).inBand(), "NIS 0.5 of dim 1 is inside");
        check(s.nis.get(3).inBand() && !s.nis.get(4).inBand(), "dim 3: 9.0 inside, 9.5 outside (high 9.348)");
        near(s.inBandFraction(), 3.0 / 5.0, 1e-12, "fraction inside the band");
        try {
            feed(m, "POSE", gate(3000, "ekf", 1, 1.0, true, 1));
            check(false, "a gate_decision_t on the pose channel is refused");
        } catch (IOException expected) {
            check(m.snapshot().poses == 25, "the refused message adds nothing");
        }
    }

    static String mapError(String text) throws IOException {
        try {
            MapCsv.parse(new StringReader(text), "m.csv");
            return "";
        } catch (IllegalArgumentException e) {
            return e.getMessage();
        }
    }

    static void map(String file) throws IOException {
        List<MapCsv.Element> ok = MapCsv.parse(new StringReader("id,x,y\n# note\n\n4,1.5,-2\n9, 3e1 ,0\n"), "m.csv");
        check(ok.size() == 2 && ok.get(1).id == 9, "header, comment and blank line skipped");
        near(ok.get(1).x, 30.0, 0, "x parsed with spaces");
        String e1 = mapError("id,x,y\n1,0,0\n3,1.0\n");
        check(e1.startsWith("m.csv:3: expected 3 fields"), "short line named: " + e1);
        String e2 = mapError("1,0,0\na,1,2\n");
        check(e2.startsWith("m.csv:2: id is not an integer"), "bad id named: " + e2);
        String e3 = mapError("1,0,0\n2,0,0\n3,1,north\n");
        check(e3.startsWith("m.csv:3: y is not a number: 'north'"), "bad y named: " + e3);
        String e4 = mapError("1,0,0\n1,2,2\n");
        check(e4.startsWith("m.csv:2: duplicate id 1"), "duplicate id named: " + e4);
        String e5 = mapError("1,NaN,0\n");
        check(e5.startsWith("m.csv:1: x is not finite"), "NaN named: " + e5);
        List<MapCsv.Element> shipped = MapCsv.read(Paths.get(file));
        check(shipped.size() > 10, "shipped map " + file + " read: " + shipped.size() + " elements");
    }

    /** Paints a circuit with markers headless and checks the track and ellipse colours appear. */
    static void paint(String mapFile, String png) throws IOException {
        List<MapCsv.Element> map = MapCsv.read(Paths.get(mapFile));
        // The vehicle drives past the map's elements in file order, 0.5 m to their side, and each
        // decision associates the element it passes; every tenth is rejected.
        PoseModel m = new PoseModel("GATE", 5000, 500, 300);
        long utime = 0;
        for (int k = 0; k + 1 < map.size(); ++k) {
            MapCsv.Element a = map.get(k), b = map.get(k + 1);
            for (int i = 0; i < 10; ++i, utime += 100000L) {
                double t = i / 10.0;
                double x = a.x + t * (b.x - a.x) + 0.5, y = a.y + t * (b.y - a.y);
                double theta = Math.atan2(b.y - a.y, b.x - a.x);
                feed(m, "POSE", pose(utime, x, y, theta, cov(0.0004, 0.0001, 0.0009)));
                boolean accepted = (utime / 100000L) % 10 != 3;
                feed(m, "GATE", gate(utime, "ekf", 2, accepted ? 0.3 + (i % 5) : 25.0, accepted, (t < 0.5 ? a : b).id));
            }
        }
        PosePanel panel = new PosePanel(m, "POSE + GATE", map, "map " + map.size() + " elements");
        panel.setSize(720, 620);
        BufferedImage img = new BufferedImage(720, 620, BufferedImage.TYPE_INT_RGB);
        panel.paint(img.createGraphics());
        int track = count(img, PosePanel.TRACK), ellipse = count(img, PosePanel.ELLIPSE);
        int mapPx = count(img, PosePanel.MAP), band = count(img, PosePanel.BAND);
        int rejected = count(img, PosePanel.REJECTED);
        check(rejected > 100, "rejected decisions painted red: " + rejected);
        check(track > 200, "track pixels painted: " + track);
        check(ellipse > 60, "ellipse pixels painted: " + ellipse);
        check(mapPx > 100, "map pixels painted: " + mapPx);
        check(band > 1000, "chi-square band pixels painted: " + band);
        if (png != null) {
            ImageIO.write(img, "png", new File(png));
        }
    }

    /** Pixels of about colour c. */
    static int count(BufferedImage img, java.awt.Color c) {
        int n = 0;
        for (int y = 0; y < img.getHeight(); ++y) {
            for (int x = 0; x < img.getWidth(); ++x) {
                int p = img.getRGB(x, y);
                int d = Math.abs(((p >> 16) & 0xff) - c.getRed()) + Math.abs(((p >> 8) & 0xff) - c.getGreen())
                    + Math.abs((p & 0xff) - c.getBlue());
                n += d <= 40 ? 1 : 0; // antialiased edges within 40 of the colour count

            }
        }
        return n;
    }

    public static void main(String[] args) throws IOException {
        if (args.length < 1) {
            System.err.println("usage: PoseModelTest MAP_CSV [PNG_OUT]");
            System.exit(2);
        }
        ellipse();
        band();
        model();
        map(args[0]);
        paint(args[0], args.length > 1 ? args[1] : null);
        System.out.println(checks + " checks, " + failures + " failed");
        System.exit(failures == 0 ? 0 : 1);
    }
}
